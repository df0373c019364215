#pragma once
// Runs the real ftctune binary for end-to-end tests.
#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <system_error>
#include <vector>

namespace ftc::testing {

struct CliResult {
  int exit_code = -1;
  std::string out;
  std::string err;
};

inline std::string slurp(const std::filesystem::path& p) {
  std::ifstream in(p);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

// The scratch directories of this test process, removed when it exits (ctest runs each test
// in its own process) so that test runs do not pile up in /tmp. FTC_KEEP_TEST_DIRS=1 keeps
// them for a look after a failure.
class ScratchDirs {
 public:
  ScratchDirs() = default;
  ScratchDirs(const ScratchDirs&) = delete;
  ScratchDirs& operator=(const ScratchDirs&) = delete;
  ~ScratchDirs() {
    if (std::getenv("FTC_KEEP_TEST_DIRS")) return;
    for (const auto& d : dirs_) {
      std::error_code ec;  // best effort: never throw from a destructor
      std::filesystem::remove_all(d, ec);
    }
  }
  void add(const std::filesystem::path& d) { dirs_.push_back(d); }

 private:
  std::vector<std::filesystem::path> dirs_;
};

inline std::filesystem::path fresh_dir(const std::string& name) {
  static ScratchDirs dirs;
  const auto d = std::filesystem::temp_directory_path() /
                 ("ftctune-test-" + name + "-" + std::to_string(::getpid()));
  std::filesystem::remove_all(d);
  std::filesystem::create_directories(d);
  dirs.add(d);
  return d;
}

// `args` is a shell-quoted argument string; runs from the source directory, with the variables
// `env` sets ("NAME=value ...") in its environment.
inline CliResult run_cli(const std::string& args, const std::filesystem::path& scratch,
                         const std::string& env = "") {
  const auto out = scratch / "stdout.txt", err = scratch / "stderr.txt";
  const std::string cmd = "cd '" FTC_SOURCE_DIR "' && " + env + " '" FTC_CLI "' " + args + " >'" +
                          out.string() + "' 2>'" + err.string() + "'";
  const int status = std::system(cmd.c_str());
  CliResult r;
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  r.out = slurp(out);
  r.err = slurp(err);
  return r;
}

}  // namespace ftc::testing
