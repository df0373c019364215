#pragma once
// Shared by the libFuzzer targets. Bad input deserves an ftc::InputError; anything else that
// comes out of a target (another exception, a failed check, a crash, a sanitizer report) is a
// finding, which libFuzzer saves as a crash input.
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <string>
#include <typeinfo>

#include <unistd.h>

#include "ftc/sim/input_error.hpp"

namespace ftc::fuzz {

// A directory of this process's own for a target that writes the files a job names (a scenarios
// file), made on first use as ftctune-fuzz-<target>-<pid> and removed at exit.
inline const std::filesystem::path& scratch_dir(const char* target) {
  static const struct Dir {
    std::filesystem::path path;
    explicit Dir(const char* t)
        : path(std::filesystem::temp_directory_path() /
               ("ftctune-fuzz-" + std::string(t) + "-" + std::to_string(::getpid()))) {
      std::filesystem::create_directories(path);
    }
    ~Dir() {
      std::error_code ec;
      std::filesystem::remove_all(path, ec);
    }
  } dir(target);
  return dir.path;
}

[[noreturn]] inline void finding(const std::string& what) {
  std::fprintf(stderr, "FINDING: %s\n", what.c_str());
  std::abort();
}

// Runs `body`: an InputError ends it quietly, any other exception is a finding.
template <class F>
void input_errors_only(F&& body) {
  try {
    body();
  } catch (const InputError&) {
  } catch (const std::exception& e) {
    finding(std::string(typeid(e).name()) + " escaped: " + e.what());
  }
}

// Runs `body` on input the loaders accepted: nothing may come out of it, InputError included.
template <class F>
void nothing_escapes(const char* step, F&& body) {
  try {
    body();
  } catch (const std::exception& e) {
    finding(std::string(step) + ": " + typeid(e).name() + ": " + e.what());
  }
}

}  // namespace ftc::fuzz
