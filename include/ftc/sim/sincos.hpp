#pragma once
// sin and cos of an argument that moves in small steps (the RK4 stages of a state, or ω t for
// consecutive stage times). From an anchor a with s = sin a, c = cos a computed by libm,
//
//   sin(a + δ) = s cos δ + c sin δ,   cos(a + δ) = c cos δ - s sin δ
//
// with sin δ and cos δ from their Taylor series. For |δ| ≤ kReach = 0.02 the first omitted
// terms (δ⁹/9!, δ⁸/8!) are below 1e-18, so the result is within about one ulp of libm's, at a
// fifth of the cost. Farther away the tracker re-anchors with libm. It is deterministic: the
// same sequence of arguments gives the same bits.
#include <cmath>
#include <limits>

namespace ftc::sim {

class SinCosTracker {
 public:
  static constexpr double kReach = 0.02;

  void eval(double x, double& s, double& c) {
    const double d = x - anchor_;
    if (!(std::abs(d) <= kReach)) {  // also true for the NaN anchor of a fresh tracker
      anchor_ = x;
      s_ = std::sin(x);
      c_ = std::cos(x);
      s = s_;
      c = c_;
      return;
    }
    const double d2 = d * d;
    const double sd = d * (1.0 + d2 * (-1.0 / 6 + d2 * (1.0 / 120 + d2 * (-1.0 / 5040))));
    const double cd = 1.0 + d2 * (-0.5 + d2 * (1.0 / 24 + d2 * (-1.0 / 720 + d2 * (1.0 / 40320))));
    s = s_ * cd + c_ * sd;
    c = c_ * cd - s_ * sd;
  }

 private:
  double anchor_ = std::numeric_limits<double>::quiet_NaN();
  double s_ = 0.0, c_ = 1.0;
};

}  // namespace ftc::sim
