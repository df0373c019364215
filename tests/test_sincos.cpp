// The hot loop's cheap sines and cosines (sim_core/sincos.hpp) against libm.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "sincos.hpp"

using namespace ftc::sim;

TEST(SinCosTracker, MatchesLibmForSmallAndLargeSteps) {
  SinCosTracker tr;
  double x = -3.0, worst = 0.0;
  // Small steps (stay near the anchor), then jumps that force re-anchoring.
  for (int k = 0; k < 20000; ++k) {
    x += (k % 1000 == 999) ? 0.7 : 1.3e-3;
    double s, c;
    tr.eval(x, s, c);
    worst = std::max({worst, std::abs(s - std::sin(x)), std::abs(c - std::cos(x))});
  }
  EXPECT_LT(worst, 4e-16);
}

TEST(Phasor, StaysWithinLibmBetweenAnchors) {
  // The simulator's use: half steps of 0.5 ms for 30 s, re-anchored every kMaxSteps advances.
  // Against libm at the rounded argument ω t + φ, whose own rounding (a few ulp of ω t) is the
  // larger error at high frequencies.
  const double dt = 5e-4;
  for (const double omega : {1.0, 3.0, 50.0}) {
    Phasor p(omega, 0.4, dt);
    double worst = 0.0;
    for (int n = 0; n <= 60000; ++n) {
      const double t = n * dt;
      if (n % Phasor::kMaxSteps == 0)
        p.anchor(t);
      else
        p.advance();
      const double a = omega * t + 0.4;
      worst = std::max({worst, std::abs(p.sin() - std::sin(a)), std::abs(p.cos() - std::cos(a))});
    }
    EXPECT_LT(worst, 1e-14 + 4 * omega * 30.0 * 0x1p-52) << "omega " << omega;
    EXPECT_GT(worst, 0.0) << "omega " << omega;  // rotation is not libm: the test can tell
  }
}
