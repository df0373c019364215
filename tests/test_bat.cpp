#include <gtest/gtest.h>

#include <cmath>

#include "ftc/tune/optimizers/bat.hpp"
#include "ftc/tune/optimizers/optimizer.hpp"
#include "ftc/tune/optimizers/random_search.hpp"
#include "test_functions.hpp"

using namespace ftc::tune;
using namespace ftc::testing;

// Tolerances are the worst case over seeds 1–10 measured with this implementation (M = 30,
// T = 300), rounded up; the Bat algorithm with the paper's settings refines only down to about
// its mean loudness, so it gets close rather than exact.
TEST(BatAlgorithm, SolvesSphereInTwoToFiveDimensions) {
  const double tolerance[] = {0, 0, 0.005, 0.05, 0.1, 0.15};
  for (std::size_t d = 2; d <= 5; ++d) {
    double bat_total = 0, random_total = 0;
    for (std::uint64_t seed = 1; seed <= 3; ++seed) {
      const SearchSpace s = box(d, -5, 5);
      const OptimizationResult r = solve(bat(30, 300), seed, s, sphere);
      expect_monotone(r);
      EXPECT_LT(sphere(r.best), tolerance[d]) << "d = " << d << ", seed " << seed;
      EXPECT_DOUBLE_EQ(r.best_fitness, 1.0 / (1.0 + sphere(r.best)));
      bat_total += sphere(r.best);
      random_total += sphere(solve(random(30, 300), seed, s, sphere).best);
    }
    // What the algorithm buys: random search with the same budget ends clearly worse.
    if (d >= 3) {
      EXPECT_LT(3 * bat_total, random_total) << "d = " << d;
    }
  }
}

TEST(BatAlgorithm, GetsCloseOnRosenbrock) {
  for (std::size_t d = 2; d <= 5; ++d) {
    const SearchSpace s = box(d, -2, 2);
    const OptimizationResult r = solve(bat(30, 300), 7, s, rosenbrock);
    expect_monotone(r);
    const double first = 1.0 / r.history.front().best_fitness - 1.0;
    const double last = rosenbrock(r.best);
    EXPECT_LT(last, d == 2 ? 0.05 : 15.0) << "d = " << d;
    EXPECT_LT(last, 0.05 * first) << "d = " << d << ": initial best " << first;
  }
}

TEST(BatAlgorithm, EvaluatesPopulationTimesIterationsPlusOne) {
  CheckingEvaluator ev(box(3, -1, 1), sphere);
  const OptimizationResult r = solve(bat(7, 9), 1, box(3, -1, 1), sphere, &ev);
  EXPECT_EQ(ev.evaluations, 7 * 10);
  EXPECT_EQ(r.evaluations, 70);
  ASSERT_EQ(r.history.size(), 10u);  // iteration 0 (initial population) to 9
  EXPECT_EQ(r.history.back().iteration, 9);
  EXPECT_EQ(r.history.back().evaluations, 70);
}

TEST(BatAlgorithm, FrequencyMovesBatsTowardTheBest) {
  const SearchSpace s = box(2, -10, 10);
  const Decision x{4.0, -2.0}, best{-1.0, 3.0};
  for (double f : {0.25, 0.5, 1.0}) {
    Decision v{0.0, 0.0};
    const Decision c = bat_frequency_move(s, x, v, best, f);
    // v = (best - x) f: the move points at the best, never away (eq. 36's sign, corrected).
    EXPECT_DOUBLE_EQ(v[0], -5.0 * f);
    EXPECT_DOUBLE_EQ(v[1], 5.0 * f);
    const double before = std::hypot(x[0] - best[0], x[1] - best[1]);
    const double after = std::hypot(c[0] - best[0], c[1] - best[1]);
    EXPECT_LT(after, before) << "f = " << f;
  }
  Decision v{0.0, 0.0};
  const Decision c = bat_frequency_move(s, x, v, Decision{-100.0, 100.0}, 2.0);
  EXPECT_EQ(c, (Decision{-10.0, 10.0}));  // clamped to the bounds
}

TEST(BatAlgorithm, LoudnessAndPulseRateChangeOnAcceptedMovesOnly) {
  const SearchSpace s = box(2, -5, 5);
  BatSettings c;
  c.population = 12;
  c.iterations = 0;
  BatAlgorithm ba(c, 3, s);
  CheckingEvaluator ev(s, sphere);
  ba.initialize(ev);
  int accepted = 0, rejected = 0;
  for (int t = 1; t <= 15; ++t) {
    const std::vector<BatAlgorithm::Bat> before = ba.bats();
    ba.iterate(ev);
    const double r_t = c.pulse_rate * (1 - std::exp(-c.pulse_rate_growth * t));
    for (std::size_t i = 0; i < before.size(); ++i) {
      const BatAlgorithm::Bat& b0 = before[i];
      const BatAlgorithm::Bat& b1 = ba.bats()[i];
      if (b1.x != b0.x) {
        ++accepted;
        EXPECT_GE(b1.fitness, b0.fitness);
        EXPECT_DOUBLE_EQ(b1.loudness, c.loudness_decay * b0.loudness);
        EXPECT_DOUBLE_EQ(b1.pulse_rate, r_t);
      } else {
        ++rejected;
        EXPECT_EQ(b1.loudness, b0.loudness);
        EXPECT_EQ(b1.pulse_rate, b0.pulse_rate);
        EXPECT_EQ(b1.fitness, b0.fitness);
      }
    }
    EXPECT_GE(ba.best_fitness(), 0.0);
  }
  EXPECT_GT(accepted, 0);
  EXPECT_GT(rejected, 0);
}

TEST(BatAlgorithm, SameSeedSameRunOtherSeedOtherRun) {
  const SearchSpace s = box(3, -5, 5);
  const OptimizationResult a = solve(bat(10, 10), 5, s, rosenbrock);
  const OptimizationResult b = solve(bat(10, 10), 5, s, rosenbrock);
  const OptimizationResult c = solve(bat(10, 10), 6, s, rosenbrock);
  ASSERT_EQ(a.history.size(), b.history.size());
  for (std::size_t i = 0; i < a.history.size(); ++i) {
    EXPECT_EQ(a.history[i].best, b.history[i].best);
    EXPECT_EQ(a.history[i].extras, b.history[i].extras);
  }
  EXPECT_NE(a.history.front().best, c.history.front().best);
}
