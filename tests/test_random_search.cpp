#include <gtest/gtest.h>

#include <cmath>
#include <nlohmann/json.hpp>

#include "ftc/tune/optimizers/optimizer.hpp"
#include "ftc/tune/optimizers/random_search.hpp"
#include "test_functions.hpp"

using namespace ftc::tune;
using namespace ftc::testing;

TEST(RandomSearch, SameBudgetMonotoneAndInBounds) {
  CheckingEvaluator ev(box(2, -5, 5), sphere);
  const OptimizationResult r = solve(random(10, 10), 9, box(2, -5, 5), sphere, &ev);
  EXPECT_EQ(ev.evaluations, 110);
  expect_monotone(r);
  EXPECT_TRUE(r.history.back().extras.empty());  // no loudness, no pulses
}
