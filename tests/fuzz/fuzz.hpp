#pragma once
// Shared by the libFuzzer targets. Bad input deserves an ftc::InputError; anything else that
// comes out of a target (another exception, a failed check, a crash, a sanitizer report) is a
// finding, which libFuzzer saves as a crash input.
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <string>
#include <typeinfo>

#include "ftc/sim/input_error.hpp"

namespace ftc::fuzz {

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
