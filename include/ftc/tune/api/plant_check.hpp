#pragma once
// `ftctune plant check LIB`: what a plant plugin must satisfy before anyone tunes with it
// (docs/plugins.md), checked at random states of its default parameters:
//   - G(X) G⁺(X) = I_n (the controllers' right inverse), to a relative 1e-9;
//   - f(X), G(X) and G⁺(X) finite, and the same bits when evaluated twice;
//   - its actuator trim (when it has one) inside its own limits: lo ≤ 0 ≤ hi, lo < hi;
//   - its SIMD lanes equal one lane, bit for bit, on every instruction set this machine runs:
//     a pack of simulations (every controller type, a fault, the default initial state and ones
//     drawn around it) against the same simulations one at a time;
//   - optionally f and G against the user's Python model (`--against model.py`, a file defining
//     f(x, p) and G(x, p), x the 2n state values and p the parameters by name): the worst
//     relative difference, which fails the check above `tolerance`.
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace ftc::tune {

struct PlantCheckOptions {
  int states = 200;                // random states drawn
  std::uint64_t seed = 1;          // of those states
  std::filesystem::path against;   // a Python model; empty: none
  std::string python = "python3";  // the interpreter that runs it
  double tolerance = 1e-9;         // of the Python comparison (relative)
};

struct PlantCheckItem {
  std::string name;  // "G G⁺ = I"
  bool passed = false;
  std::string detail;  // what was measured
};

struct PlantCheckReport {
  std::string model;  // plugin:NAME
  std::string file;
  int axes = 0, actuators = 0;
  std::vector<PlantCheckItem> items;
  bool passed() const {
    for (const PlantCheckItem& i : items)
      if (!i.passed) return false;
    return true;
  }
};

// Loads the library (InputError, exit 2, for one that cannot be loaded) and checks it.
PlantCheckReport check_plant_plugin(const std::filesystem::path& library,
                                    const PlantCheckOptions& options = {});

}  // namespace ftc::tune
