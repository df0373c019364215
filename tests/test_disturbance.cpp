#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "ftc/sim/disturbance.hpp"
#include "ftc/sim/scenario.hpp"
#include "sincos.hpp"

using namespace ftc::sim;

TEST(Disturbance, PaperDisturbance) {
  const Disturbance d(Scenario::paper().disturbance);
  const double t = 1.7;
  const Vec3 v = d.at<3>(t);
  EXPECT_DOUBLE_EQ(v[0], 0.5 * std::sin(t));
  EXPECT_DOUBLE_EQ(v[1], 0.5 * std::cos(2 * t));
  EXPECT_DOUBLE_EQ(v[2], 0.5 * std::sin(3 * t));
}

TEST(Disturbance, BlockEvaluationMatchesPointwise) {
  const Disturbance d({{2, Shape::sin, 1.0, 2.0, 0.5},
                       {2, Shape::cos, 0.25, 1.0, 0.0},
                       {3, Shape::cos, 0.7, 3.0, -1.0}});
  const std::vector<double> t = {0.0, 0.3, 2.5, 2.5005, 17.25};
  std::vector<Vec3> out(t.size());
  // With the same sinusoid values the block gives the pointwise sums bit for bit ...
  d.evaluate(
      t.size(),
      [&](std::size_t i, std::size_t k, Shape shape) {
        const DisturbanceTerm& term = d.terms()[i];
        const double x = term.frequency * t[k] + term.phase;
        return shape == Shape::sin ? std::sin(x) : std::cos(x);
      },
      [&](std::size_t k) -> Vec3& { return out[k]; });
  for (std::size_t k = 0; k < t.size(); ++k) EXPECT_EQ(out[k], d.at<3>(t[k])) << t[k];
  // ... and with the sinusoids from phasors (what the simulator does) within 1e-14.
  std::vector<Phasor> p = phasors_of(d.terms(), 5e-4);
  for (Phasor& q : p) q.anchor(2.5);
  for (int n = 0; n < 20; ++n)
    for (Phasor& q : p) q.advance();
  Vec3 v;
  d.evaluate(
      1,
      [&](std::size_t i, std::size_t, Shape shape) {
        return shape == Shape::sin ? p[i].sin() : p[i].cos();
      },
      [&](std::size_t) -> Vec3& { return v; });
  EXPECT_TRUE(v.isApprox(d.at<3>(2.51), 1e-14));
}

TEST(Disturbance, TermsOnOneAxisAddWithPhase) {
  const Disturbance d({{2, Shape::sin, 1.0, 2.0, 0.5}, {2, Shape::cos, 0.25, 1.0, 0.0}});
  const Vec3 v = d.at<3>(0.3);
  EXPECT_EQ(v[0], 0.0);
  EXPECT_DOUBLE_EQ(v[1], std::sin(2.0 * 0.3 + 0.5) + 0.25 * std::cos(0.3));
}
