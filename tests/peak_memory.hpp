#pragma once
// How much a piece of work adds to a process's peak resident set, measured in a child process
// (fork): the child's peak (VmHWM) once the work is done, over its resident size when it began.
// The memory-by-design tests (issue 29) compare two sizes of the same work.
#include <fcntl.h>
#include <malloc.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <fstream>
#include <functional>
#include <string>

namespace ftc::testing {

// Resets the process's peak resident set to its current size (Linux's clear_refs "5").
inline bool reset_peak() {
  const int fd = ::open("/proc/self/clear_refs", O_WRONLY | O_CLOEXEC);
  if (fd < 0) return false;
  const bool done = ::write(fd, "5", 1) == 1;
  ::close(fd);
  return done;
}

// Why a peak cannot be measured here, nullptr when it can.
inline const char* why_no_peak() {
#if defined(__SANITIZE_ADDRESS__)
  return "AddressSanitizer's quarantine keeps freed blocks: no peak to measure";
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
  return "AddressSanitizer's quarantine keeps freed blocks: no peak to measure";
#endif
#endif
  if (!reset_peak())
    return "this system does not let a process reset its peak (/proc/self/clear_refs)";
  return nullptr;
}

// A "Name: N kB" line of /proc/self/status, -1 when it is missing.
inline long status_kb(const std::string& name) {
  std::ifstream in("/proc/self/status");
  for (std::string line; std::getline(in, line);)
    if (line.rfind(name, 0) == 0) return std::stol(line.substr(name.size()));
  return -1;
}

// The kB the peak grew by while `work` ran in a child process; -1 when the work failed (it
// returned false or threw) or the child could not say.
inline long peak_growth_kb(const std::function<bool()>& work) {
  int fd[2];
  if (::pipe(fd) != 0) return -1;
  const pid_t pid = ::fork();
  if (pid < 0) return -1;
  if (pid == 0) {
    ::close(fd[0]);
    // The child starts with the parent's heap, freed blocks included, resident: work that reused
    // them would not raise the peak. They go back to the system first, and the peak is reset to
    // what is left (Linux's clear_refs "5"), so that the peak counts every page the work touches.
    ::malloc_trim(0);
    const bool reset = reset_peak();
    const long before = status_kb("VmRSS:");
    bool done = false;
    try {
      done = work();
    } catch (...) {
      done = false;
    }
    const long peak = status_kb("VmHWM:");
    const long grown = done && reset && before >= 0 && peak >= 0 ? peak - before : -1;
    const bool sent = ::write(fd[1], &grown, sizeof grown) == sizeof grown;
    ::_exit(done && sent ? 0 : 1);
  }
  ::close(fd[1]);
  long grown = -1;
  if (::read(fd[0], &grown, sizeof grown) != sizeof grown) grown = -1;
  ::close(fd[0]);
  int status = 0;
  ::waitpid(pid, &status, 0);
  return WIFEXITED(status) && WEXITSTATUS(status) == 0 ? grown : -1;
}

}  // namespace ftc::testing
