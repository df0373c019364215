#pragma once
// Test functions for the optimisers (sphere and Rosenbrock with the optimum off-centre), a
// fitness that checks every candidate against the bounds, and shorthands for settings.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "ftc/tune/optimizers/optimizer.hpp"

namespace ftc::testing {

using namespace ftc::tune;

inline SearchSpace box(std::size_t d, double lo, double hi) {
  SearchSpace s;
  for (std::size_t j = 0; j < d; ++j) {
    s.names.push_back(std::string(1, static_cast<char>('a' + j)));  // a, b, c, ...
    s.lower.push_back(lo);
    s.upper.push_back(hi);
  }
  return s;
}

inline double sphere(const Decision& x) {
  double f = 0;
  for (double v : x) f += (v - 1.0) * (v - 1.0);  // optimum at (1, …, 1), off-centre on purpose
  return f;
}

inline double rosenbrock(const Decision& x) {
  double f = 0;
  for (std::size_t j = 0; j + 1 < x.size(); ++j)
    f += 100 * std::pow(x[j + 1] - x[j] * x[j], 2) + std::pow(1 - x[j], 2);
  return f;
}

// Counts evaluations, records the batch sizes and checks every candidate against the bounds.
class CheckingEvaluator final : public BatchFitness {
 public:
  CheckingEvaluator(SearchSpace space, double (*f)(const Decision&))
      : space_(std::move(space)), f_(f) {}
  std::vector<double> operator()(const std::vector<Decision>& batch) override {
    batches.push_back(batch.size());
    std::vector<double> J;
    for (const Decision& x : batch) {
      if (!space_.contains(x)) ++out_of_bounds;
      ++evaluations;
      J.push_back(1.0 / (1.0 + f_(x)));  // fitness: larger is better, 1 at the optimum
    }
    return J;
  }
  std::vector<std::size_t> batches;  // the size of every batch, in order
  std::int64_t evaluations = 0;
  int out_of_bounds = 0;

 private:
  SearchSpace space_;
  double (*f_)(const Decision&);
};

inline AlgorithmPtr bat(int population, int iterations) {
  return make_algorithm({{"type", "bat"}, {"population", population}, {"iterations", iterations}});
}
inline AlgorithmPtr random(int population, int iterations) {
  return make_algorithm(
      {{"type", "random"}, {"population", population}, {"iterations", iterations}});
}

inline OptimizationResult solve(const AlgorithmPtr& c, std::uint64_t seed, const SearchSpace& s,
                                double (*f)(const Decision&), CheckingEvaluator* ev_out = nullptr) {
  CheckingEvaluator ev(s, f);
  auto opt = c->make(seed, s);
  OptimizationResult r = run_optimizer(*opt, ev);
  EXPECT_EQ(ev.out_of_bounds, 0);
  EXPECT_EQ(r.evaluations, ev.evaluations);
  if (ev_out) *ev_out = ev;
  return r;
}

inline void expect_monotone(const OptimizationResult& r) {
  for (std::size_t i = 1; i < r.history.size(); ++i)
    EXPECT_GE(r.history[i].best_fitness, r.history[i - 1].best_fitness) << "iteration " << i;
}

}  // namespace ftc::testing
