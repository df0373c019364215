#pragma once
// Cheap sin and cos for the hot loop, in two forms.
//
// SinCosTracker: sin and cos of an argument that moves in small steps (an attitude angle from
// one RK4 stage and sample to the next). From an anchor a with s = sin a, c = cos a by
// math::sincos (ftc/sim/elementary.hpp; out of line, as re-anchoring is rare and the loop stays
// small),
//
//   sin(a + δ) = s cos δ + c sin δ,   cos(a + δ) = c cos δ - s sin δ
//
// with sin δ and cos δ from their Taylor series. For |δ| ≤ kReach = 0.02 the first omitted
// terms (δ⁹/9!, δ⁸/8!) are below 1e-18, so the result is within about one ulp of the exact values,
// at a fifth of the cost. Farther away the tracker re-anchors. It is deterministic: the same
// sequence of arguments gives the same bits.
#include <cmath>
#include <limits>
#include <vector>

#include "ftc/sim/elementary.hpp"
#include "ftc/sim/types.hpp"

namespace ftc::sim {

class SinCosTracker {
 public:
  static constexpr double kReach = 0.02;

  // The same operations as the batch simulator's AngleTracker (lanes/angle_tracker.hpp),
  // so that a plant's f(x, ws) (plants/<plant>_dynamics.hpp) and its lane code give the same
  // bits: after re-anchoring, the series runs with δ = 0.
  FTC_HOT_INLINE void eval(double x, double& s, double& c) {
    if (!(std::abs(x - anchor_) <= kReach)) {  // also true for the NaN anchor of a fresh tracker
      anchor_ = x;
      math::sincos(x, s_, c_);
    }
    const double d = x - anchor_;
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

// Phasor: sin and cos of ω t + φ on a uniform time grid t_n = t_a + n·dt, for the sinusoids of
// the disturbance and of bias faults. anchor(t) sets the value at t with math::sincos; each
// advance() rotates it through the fixed angle ω·dt,
//
//   (s, c) ← (s C + c S, c C − s S),   C = cos ω dt, S = sin ω dt,
//
// four multiplications instead of a sin and a cos. A rotation adds about one ulp of error, so
// callers re-anchor at least every kMaxSteps advances, which keeps the values within 1e-14 of
// the exact values at the paper's frequencies (tests/test_plant.cpp; at large ω t the rounding of
// the argument ω t + φ itself, a few ulp of it, dominates both).
class Phasor {
 public:
  static constexpr int kMaxSteps = 32;

  Phasor() = default;
  Phasor(double omega, double phase, double dt) : omega_(omega), phase_(phase) {
    math::sincos(omega * dt, S_, C_);
  }

  void anchor(double t) {
    const double a = omega_ * t + phase_;
    math::sincos(a, s_, c_);
  }
  void advance() {
    const double s = s_ * C_ + c_ * S_;
    c_ = c_ * C_ - s_ * S_;
    s_ = s;
  }
  double sin() const { return s_; }
  double cos() const { return c_; }

 private:
  double omega_ = 0.0, phase_ = 0.0;
  double C_ = 1.0, S_ = 0.0;
  double s_ = 0.0, c_ = 1.0;
};

// One phasor stepping by dt, not yet anchored, per sinusoid of `items` (anything with
// `frequency` in rad/s and `phase` in rad: disturbance terms, faults).
template <class Items>
std::vector<Phasor> phasors_of(const Items& items, double dt) {
  std::vector<Phasor> p;
  p.reserve(items.size());
  for (const auto& item : items) p.emplace_back(item.frequency, item.phase, dt);
  return p;
}

}  // namespace ftc::sim
