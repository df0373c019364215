#include <gtest/gtest.h>

#include <cmath>
#include <nlohmann/json.hpp>

#include "ftc/tune/optimizers/optimizer.hpp"
#include "ftc/tune/optimizers/random_search.hpp"
#include "test_functions.hpp"

using namespace ftc::tune;
using namespace ftc::testing;

TEST(Optimizer, ObserverCanStopTheRun) {
  int calls = 0;
  CheckingEvaluator ev(box(2, -5, 5), sphere);
  auto opt = bat(5, 10)->make(1, box(2, -5, 5));
  const OptimizationResult r = run_optimizer(*opt, ev, [&](const HistoryRow& h, const Optimizer&) {
    ++calls;
    return h.iteration < 3;
  });
  EXPECT_EQ(calls, 4);
  EXPECT_FALSE(r.completed);
  EXPECT_EQ(r.evaluations, 20);
}

TEST(Optimizer, ResumeFromSavedStateContinuesExactly) {
  for (const AlgorithmPtr& c : {bat(6, 8), random(6, 8)}) {
    const SearchSpace s = box(3, -2, 2);
    CheckingEvaluator ev(s, rosenbrock);
    auto full = c->make(11, s);
    const OptimizationResult uninterrupted = run_optimizer(*full, ev);

    std::string saved;
    auto first = c->make(11, s);
    run_optimizer(*first, ev, [&](const HistoryRow& h, const Optimizer& o) {
      saved = o.state().dump();  // through text, as a checkpoint store would keep it
      return h.iteration < 3;
    });
    const nlohmann::json state = nlohmann::json::parse(saved);
    auto second = c->make(999, s);  // the seed must not matter: the state has the engine
    const OptimizationResult resumed = run_optimizer(*second, ev, {}, &state);
    ASSERT_EQ(resumed.history.size(), uninterrupted.history.size());
    for (std::size_t i = 0; i < resumed.history.size(); ++i) {
      EXPECT_EQ(resumed.history[i].best, uninterrupted.history[i].best) << "iteration " << i;
      EXPECT_EQ(resumed.history[i].best_fitness, uninterrupted.history[i].best_fitness);
    }
    EXPECT_TRUE(resumed.completed);
    EXPECT_EQ(resumed.evaluations, uninterrupted.evaluations);
  }
}
