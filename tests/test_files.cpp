// tuner/io/files: every output lands whole or not at all, and only in place of a regular file.
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <filesystem>
#include <fstream>
#include <string>

#include "cli_runner.hpp"
#include "ftc/tune/io/files.hpp"
#include "ftc/tune/report/report.hpp"

namespace fs = std::filesystem;
using ftc::testing::fresh_dir;
using ftc::testing::slurp;
using ftc::tune::commit_file;
using ftc::tune::OutputError;
using ftc::tune::write_file_atomic;

namespace {

std::size_t entries(const fs::path& dir) {
  std::size_t n = 0;
  for ([[maybe_unused]] const auto& e : fs::directory_iterator(dir)) ++n;
  return n;
}

}  // namespace

// A symbolic link, a FIFO and a directory are refused (OutputError) and left as they were: what
// a link points to is not written through or replaced, and a FIFO is not opened (no hang).
TEST(Files, TargetThatIsNotARegularFileIsRefusedAndLeftAlone) {
  const fs::path dir = fresh_dir("files-non-regular");
  write_file_atomic(dir / "precious", "keep me\n");
  fs::create_symlink(dir / "precious", dir / "link");
  ASSERT_EQ(::mkfifo((dir / "fifo").c_str(), 0600), 0);
  fs::create_directory(dir / "sub");
  for (const char* name : {"link", "fifo", "sub"}) {
    try {
      write_file_atomic(dir / name, "new\n");
      ADD_FAILURE() << name << " was written";
    } catch (const OutputError& e) {
      EXPECT_NE(std::string(e.what()).find((dir / name).string() + " is a"), std::string::npos)
          << e.what();
    }
  }
  EXPECT_TRUE(fs::is_symlink(dir / "link"));
  EXPECT_TRUE(fs::is_fifo(dir / "fifo"));
  EXPECT_EQ(slurp(dir / "precious"), "keep me\n");
  EXPECT_EQ(entries(dir), 4u);  // no temporary file left behind
  // A regular file is replaced, and a broken link is still a link.
  write_file_atomic(dir / "precious", "new\n");
  EXPECT_EQ(slurp(dir / "precious"), "new\n");
  fs::create_symlink(dir / "nowhere", dir / "dangling");
  EXPECT_THROW(write_file_atomic(dir / "dangling", "x"), OutputError);
  EXPECT_FALSE(fs::exists(dir / "nowhere"));
}

// commit_file (how gnuplot's figures take their place): a failed sync or rename (the
// FTCTUNE_FAIL_IO seam) removes the new file and leaves the old one whole.
TEST(Files, CommitFileFailureLeavesTheOldFile) {
  const fs::path dir = fresh_dir("files-commit");
  write_file_atomic(dir / "figure.png", "old");
  for (int step : {1, 2}) {
    std::ofstream(dir / "figure.png.partial") << "new";
    ftc::tune::inject_io_failure(step);
    EXPECT_THROW(commit_file(dir / "figure.png.partial", dir / "figure.png"),
                 fs::filesystem_error)
        << step;
    ftc::tune::inject_io_failure(0);
    EXPECT_EQ(slurp(dir / "figure.png"), "old") << step;
    EXPECT_FALSE(fs::exists(dir / "figure.png.partial")) << step;
  }
  std::ofstream(dir / "figure.png.partial") << "new";
  fs::create_symlink(dir / "figure.png", dir / "link.png");
  EXPECT_THROW(commit_file(dir / "figure.png.partial", dir / "link.png"), OutputError);
  EXPECT_FALSE(fs::exists(dir / "figure.png.partial"));
  std::ofstream(dir / "figure.png.partial") << "new";
  commit_file(dir / "figure.png.partial", dir / "figure.png");
  EXPECT_EQ(slurp(dir / "figure.png"), "new");
}

TEST(Files, FigureIsWholeOnlyWithItsEnd) {
  const fs::path dir = fresh_dir("files-figure");
  const std::string png_head("\x89PNG\r\n\x1a\n", 8);
  const std::string iend("\0\0\0\0IEND\xae\x42\x60\x82", 12);
  write_file_atomic(dir / "a.png", png_head + "IHDR....." + iend);
  EXPECT_TRUE(ftc::tune::figure_is_whole(dir / "a.png"));
  write_file_atomic(dir / "a.png", png_head + "IHDR....." + iend.substr(0, 7));
  EXPECT_FALSE(ftc::tune::figure_is_whole(dir / "a.png"));
  write_file_atomic(dir / "a.png", "");
  EXPECT_FALSE(ftc::tune::figure_is_whole(dir / "a.png"));
  write_file_atomic(dir / "a.svg", "<svg>\n<g/>\n</svg>\n\n");
  EXPECT_TRUE(ftc::tune::figure_is_whole(dir / "a.svg"));
  write_file_atomic(dir / "a.svg", "<svg>\n<g/>\n</sv");
  EXPECT_FALSE(ftc::tune::figure_is_whole(dir / "a.svg"));
  EXPECT_FALSE(ftc::tune::figure_is_whole(dir / "missing.svg"));
}
