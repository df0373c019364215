#include "ftc/tune/io/files.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <system_error>

namespace ftc::tune {

void write_file_atomic(const std::filesystem::path& path, std::string_view content) {
  write_file_atomic(path, [&](const ChunkSink& sink) { sink(content); });
}

namespace {

std::atomic<int> g_fail_after{-1};  // -1: not yet read from the environment
std::atomic<int> g_fail_errno{ENOSPC};

// True when this I/O step is the one to fail (errno set as the real call would).
bool injected_failure() {
  int n = g_fail_after.load();
  if (n < 0) {
    int after = 0, error = ENOSPC;
    if (const char* e = std::getenv("FTCTUNE_FAIL_IO"))
      if (std::sscanf(e, "%d:%d", &after, &error) < 1) after = 0;
    int expected = -1;
    g_fail_after.compare_exchange_strong(expected, after);
    if (expected == -1) g_fail_errno = error;
    n = g_fail_after.load();
  }
  while (n > 0) {
    if (g_fail_after.compare_exchange_weak(n, n - 1)) {
      if (n == 1) {
        errno = g_fail_errno.load();
        return true;
      }
      return false;
    }
  }
  return false;
}

[[noreturn]] void io_error(const std::string& step, const std::filesystem::path& p, int error) {
  throw std::filesystem::filesystem_error(step, p, std::error_code(error, std::generic_category()));
}

}  // namespace

void refuse_non_regular_target(const std::filesystem::path& path) {
  struct stat st {};
  if (::lstat(path.c_str(), &st) != 0) {
    if (errno == ENOENT) return;
    io_error("cannot inspect", path, errno);
  }
  if (S_ISREG(st.st_mode)) return;
  const char* kind = S_ISLNK(st.st_mode)    ? "a symbolic link"
                     : S_ISDIR(st.st_mode)  ? "a directory"
                     : S_ISFIFO(st.st_mode) ? "a FIFO"
                     : S_ISCHR(st.st_mode)  ? "a character device"
                     : S_ISBLK(st.st_mode)  ? "a block device"
                     : S_ISSOCK(st.st_mode) ? "a socket"
                                            : "not a regular file";
  throw OutputError(path.string() + " is " + kind +
                    ": ftctune writes its output only in place of a regular file (give another "
                    "name)");
}

void commit_file(const std::filesystem::path& written, const std::filesystem::path& target) {
  const auto fail = [&](const std::string& step, const std::filesystem::path& p, int error) {
    ::unlink(written.c_str());
    io_error(step, p, error);
  };
  try {
    refuse_non_regular_target(target);
  } catch (...) {
    ::unlink(written.c_str());
    throw;
  }
  const int fd = ::open(written.c_str(), O_RDONLY | O_CLOEXEC | O_NOFOLLOW);
  if (fd < 0) fail("cannot open", written, errno);
  if (injected_failure() || ::fsync(fd) != 0) {
    const int error = errno;
    ::close(fd);
    fail("cannot sync", target, error);
  }
  ::close(fd);
  if (injected_failure() || std::rename(written.c_str(), target.c_str()) != 0)
    fail("cannot rename into place", target, errno);
  sync_directory(target.has_parent_path() ? target.parent_path() : std::filesystem::path("."));
}

void inject_io_failure(int after, int error) {
  g_fail_errno = error;
  g_fail_after = after;
}

void write_file_atomic(const std::filesystem::path& path,
                       const std::function<void(const ChunkSink&)>& produce) {
  namespace fs = std::filesystem;
  if (path.has_parent_path()) fs::create_directories(path.parent_path());
  refuse_non_regular_target(path);
  const fs::path tmp = path.string() + ".tmp." + std::to_string(::getpid());
  // A temporary name of its own: one left by a killed process of the same pid goes, and a link
  // put there is not followed.
  ::unlink(tmp.c_str());
  const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC, 0644);
  if (fd < 0) io_error("cannot create", tmp, errno);
  const auto fail = [&](const std::string& step, int error) {
    ::close(fd);
    ::unlink(tmp.c_str());
    io_error(step, path, error);
  };
  int write_error = 0;
  try {
    produce([&](std::string_view chunk) {
      std::size_t done = 0;
      while (done < chunk.size()) {
        const ssize_t n =
            injected_failure() ? -1 : ::write(fd, chunk.data() + done, chunk.size() - done);
        if (n < 0) {
          if (errno == EINTR) continue;
          write_error = errno;
          throw std::runtime_error("write");
        }
        done += static_cast<std::size_t>(n);
      }
    });
  } catch (...) {
    if (write_error != 0) fail("cannot write", write_error);
    ::close(fd);
    ::unlink(tmp.c_str());
    throw;
  }
  // fsync before rename: after a crash the new name holds either the old or the whole new file.
  if (injected_failure() || ::fsync(fd) != 0) fail("cannot sync", errno);
  if (::close(fd) != 0) {
    const int error = errno;
    ::unlink(tmp.c_str());
    io_error("cannot write", path, error);
  }
  if (injected_failure() || std::rename(tmp.c_str(), path.c_str()) != 0) {
    const int error = errno;
    ::unlink(tmp.c_str());
    io_error("cannot rename into place", path, error);
  }
  // And the directory, so that the rename itself survives a crash.
  sync_directory(path.has_parent_path() ? path.parent_path() : fs::path("."));
}

void sync_directory(const std::filesystem::path& dir) {
  const int dfd = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (dfd < 0) io_error("cannot sync directory", dir, errno);
  // EINVAL: a file system that cannot sync directories (some network and FUSE ones).
  if (::fsync(dfd) != 0 && errno != EINVAL) {
    const int error = errno;
    ::close(dfd);
    io_error("cannot sync directory", dir, error);
  }
  ::close(dfd);
}

void move_into(const std::filesystem::path& staging, const std::filesystem::path& dir,
               const std::vector<std::string>& names) {
  for (const std::string& name : names)
    if (injected_failure() || std::rename((staging / name).c_str(), (dir / name).c_str()) != 0)
      io_error("cannot move into place", dir / name, errno);
  sync_directory(dir);
}

}  // namespace ftc::tune
