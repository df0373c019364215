#pragma once
// The valid values of a number, as the field tables of plants, controllers and files state them,
// and the message for a value outside them ("must be > 0 (got -1)").
#include <limits>
#include <string>

namespace ftc {

struct Range {
  double min = -std::numeric_limits<double>::infinity();
  bool min_open = false;
  double max = std::numeric_limits<double>::infinity();
  bool max_open = false;

  static constexpr Range any() { return {}; }
  static constexpr Range positive() { return {0.0, true}; }
  static constexpr Range non_negative() { return {0.0, false}; }
  static constexpr Range unit() { return {0.0, false, 1.0, false}; }           // [0, 1]
  static constexpr Range open_unit() { return {0.0, true, 1.0, true}; }        // (0, 1)
  static constexpr Range half_open_unit() { return {0.0, true, 1.0, false}; }  // (0, 1]
  static constexpr Range at_least(double v) { return {v, false}; }
  static constexpr Range between(double lo, double hi) { return {lo, false, hi, false}; }

  // Finite and inside.
  bool contains(double v) const;
  // "" when v is valid, else the message: "must be > 0 (got -1)", "must be a finite number".
  std::string check(double v) const;
  // "> 0", "in [0, 1]", "in the open interval (0, 1)": for messages and docs.
  std::string describe() const;
};

}  // namespace ftc
