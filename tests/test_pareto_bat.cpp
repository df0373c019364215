// The Pareto Bat algorithm (optimizers/pareto_bat.hpp): constrained domination, non-dominated
// sorting and crowding on hand-made points, and runs on a bi-objective test function.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <nlohmann/json.hpp>

#include "ftc/sim/input_error.hpp"
#include "ftc/tune/optimizers/pareto_bat.hpp"
#include "test_functions.hpp"

using namespace ftc::testing;
using ftc::InputError;
using nlohmann::json;
namespace pareto = ftc::tune::pareto;

namespace {

ObjectiveVector pt(double a, double b, double violation = 0.0) { return {{a, b}, violation}; }

// Schaffer's problem, shifted by 1 so that both goals are positive (the hypervolume's log10):
// f1 = 1 + x², f2 = 1 + (x - 2)², its Pareto set x in [0, 2]; with `limit`, the hard goal
// x <= limit (violation max(0, x/limit - 1)... here x - limit, x > 0 near it).
ObjectiveVector schaffer(const Decision& x, double limit) {
  ObjectiveVector f{{1 + x[0] * x[0], 1 + (x[0] - 2) * (x[0] - 2)}, 0.0};
  if (x[0] > limit) f.violation = x[0] - limit;
  return f;
}

std::unique_ptr<Optimizer> pareto_bat(int population, int iterations, std::uint64_t seed,
                                      const SearchSpace& s) {
  const AlgorithmPtr a = bat(population, iterations);
  EXPECT_TRUE(a->searches_front());
  return a->make_front(seed, s, 2);
}

}  // namespace

TEST(ParetoDominance, FeasibleBeatsInfeasibleLessViolationWinsElseParetoOrder) {
  EXPECT_TRUE(pareto::dominates(pt(5, 5), pt(1, 1, 0.1)));   // feasible over infeasible
  EXPECT_FALSE(pareto::dominates(pt(1, 1, 0.1), pt(5, 5)));
  EXPECT_TRUE(pareto::dominates(pt(9, 9, 0.1), pt(1, 1, 0.2)));  // less violation
  EXPECT_FALSE(pareto::dominates(pt(1, 1, 0.2), pt(9, 9, 0.1)));
  EXPECT_TRUE(pareto::dominates(pt(1, 2), pt(1, 3)));  // no worse, better in one
  EXPECT_FALSE(pareto::dominates(pt(1, 2), pt(1, 2)));  // equal: neither
  EXPECT_FALSE(pareto::dominates(pt(1, 3), pt(2, 2)));  // a trade-off: neither
  EXPECT_FALSE(pareto::dominates(pt(2, 2), pt(1, 3)));
  const double nan = std::numeric_limits<double>::quiet_NaN();
  EXPECT_TRUE(pareto::dominates(pt(1, 2), pt(1, nan)));  // NaN counts as +inf
  EXPECT_FALSE(pareto::dominates(pt(1, nan), pt(1, 2)));
}

// Capping a front (issue 42): a candidate may stop on lower bounds L only when neither its bat
// can move to it nor the archive take it, whatever its true vector at least L.
TEST(ParetoDominance, FrontCapStopsOnlyWhereNoDecisionCanChange) {
  using ftc::tune::FrontCap;
  const double inf = std::numeric_limits<double>::infinity();
  const auto archive = std::make_shared<const std::vector<ObjectiveVector>>(
      std::vector<ObjectiveVector>{pt(1, 4), pt(2, 2), pt(4, 1)});
  const FrontCap no_move{false, {}, archive};
  EXPECT_TRUE(no_move.stops(pt(3, 3)));        // (2, 2) dominates it
  EXPECT_FALSE(no_move.stops(pt(2, 2)));       // equal to a member, not dominated: it may be equal
  EXPECT_FALSE(no_move.stops(pt(1.5, 3)));     // on the front for all the bounds say
  EXPECT_FALSE(no_move.stops(pt(0.5, -inf)));  // a goal without a bound is no bound at all
  EXPECT_TRUE(no_move.stops(pt(0.5, 0.5, 0.1)));  // infeasible: never offered
  // Its bat may move: stops only where the bat dominates the bounds too.
  EXPECT_TRUE((FrontCap{true, pt(2.5, 2.5), archive}.stops(pt(3, 3))));
  EXPECT_FALSE((FrontCap{true, pt(3.5, 2.5), archive}.stops(pt(3, 3))));
  EXPECT_TRUE((FrontCap{true, pt(9, 9), archive}.stops(pt(0.5, 0.5, 0.1))));  // feasible bat
  EXPECT_FALSE((FrontCap{true, pt(1, 1, 0.2), archive}.stops(pt(0.5, 0.5, 0.1))));
  // Without an archive (one that may lose points) every feasible candidate may enter.
  EXPECT_FALSE((FrontCap{false, {}, nullptr}.stops(pt(3, 3))));
  EXPECT_TRUE((FrontCap{false, {}, nullptr}.stops(pt(3, 3, 1))));
}

TEST(ParetoSorting, FrontsOfHandMadePoints) {
  const std::vector<ObjectiveVector> p = {pt(4, 4), pt(1, 4), pt(3, 3), pt(2, 2),
                                          pt(4, 1), pt(5, 5), pt(0.5, 0.5, 1.0)};
  const auto fronts = pareto::nondominated_sort(p);
  ASSERT_EQ(fronts.size(), 5u);
  EXPECT_EQ(fronts[0], (std::vector<std::size_t>{1, 3, 4}));
  EXPECT_EQ(fronts[1], (std::vector<std::size_t>{2}));
  EXPECT_EQ(fronts[2], (std::vector<std::size_t>{0}));
  EXPECT_EQ(fronts[3], (std::vector<std::size_t>{5}));
  EXPECT_EQ(fronts[4], (std::vector<std::size_t>{6}));  // infeasible: behind every feasible one
}

TEST(ParetoSorting, CrowdingDistanceOnLog10OfEachGoal) {
  // On log10 the front is (0, 3), (1, 2), (2, 1), (3, 0): each inner point's neighbours are 2
  // apart on a range of 3 in each goal, 4/3 in all; the extremes are infinite.
  const std::vector<ObjectiveVector> p = {pt(10, 100), pt(1, 1000), pt(1000, 1), pt(100, 10)};
  const std::vector<double> d = pareto::crowding_distance(p, {0, 1, 2, 3});
  const double inf = std::numeric_limits<double>::infinity();
  EXPECT_EQ(d[1], inf);
  EXPECT_EQ(d[2], inf);
  EXPECT_NEAR(d[0], 4.0 / 3.0, 1e-12);
  EXPECT_NEAR(d[3], 4.0 / 3.0, 1e-12);
  // Unevenly spaced: (0, 3), (0.5, 2.5), (3, 0) on log10 -> inner 3/3 + 3/3 = 2.
  const std::vector<ObjectiveVector> q = {pt(1, 1000), pt(std::sqrt(10.0), std::pow(10, 2.5)),
                                          pt(1000, 1)};
  EXPECT_NEAR(pareto::crowding_distance(q, {0, 1, 2})[1], 2.0, 1e-12);
  // A goal at 0 counts as the log floor, not -inf.
  EXPECT_EQ(pareto::log_value(0.0), pareto::log_value(pareto::kLogFloor));
  EXPECT_TRUE(std::isfinite(pareto::log_value(0.0)));
}

TEST(ParetoBatAlgorithm, ArchiveIsAFeasibleNonDominatedSpreadOfTheFront) {
  const SearchSpace s = box(1, -5, 5);
  FunctionObjectives f(2, [](const Decision& x) { return schaffer(x, 1.5); });
  auto opt = pareto_bat(10, 19, 3, s);
  const OptimizationResult r = run_optimizer(*opt, f);
  EXPECT_EQ(r.evaluations, 200);
  const auto& pb = dynamic_cast<const ParetoBatAlgorithm&>(*opt);
  const auto& archive = pb.archive();
  ASSERT_GE(archive.size(), 10u);
  EXPECT_LE(archive.size(), pb.capacity());
  double lo = 1e9, hi = -1e9;
  for (std::size_t i = 0; i < archive.size(); ++i) {
    EXPECT_TRUE(archive[i].f.feasible());
    EXPECT_EQ(archive[i].f.values, schaffer(archive[i].x, 1.5).values);
    for (std::size_t k = 0; k < archive.size(); ++k)
      if (k != i) EXPECT_FALSE(pareto::dominates(archive[k].f, archive[i].f)) << i << " " << k;
    lo = std::min(lo, archive[i].x[0]);
    hi = std::max(hi, archive[i].x[0]);
  }
  // The feasible Pareto set is x in [0, 1.5]: the archive lies in it and spans most of it.
  EXPECT_GE(lo, 0.0);
  EXPECT_LE(hi, 1.5);
  EXPECT_LT(lo, 0.1);
  EXPECT_GT(hi, 1.4);
  // x*: the archive's point of least first goal.
  EXPECT_EQ(r.best[0], lo);
}

TEST(ParetoBatAlgorithm, ResumeFromSavedStateContinuesExactlyAndForgedStatesAreRefused) {
  const SearchSpace s = box(2, -5, 5);
  const auto fn = [](const Decision& x) {
    return ObjectiveVector{{1 + x[0] * x[0] + x[1] * x[1], 1 + (x[0] - 2) * (x[0] - 2)},
                           x[1] > 3 ? x[1] - 3 : 0.0};
  };
  FunctionObjectives f(2, fn);
  auto whole = pareto_bat(6, 8, 11, s);
  run_optimizer(*whole, f);
  auto first = pareto_bat(6, 8, 11, s);
  json saved;
  run_optimizer(*first, f, [&](const HistoryRow& h, const Optimizer& o) {
    saved = o.state();
    return h.iteration < 6;
  });
  const json text = json::parse(saved.dump());  // through text, as a checkpoint goes
  auto second = pareto_bat(6, 8, 999, s);       // the state has the engine: the seed is moot
  run_optimizer(*second, f, {}, &text);
  EXPECT_EQ(second->state().dump(), whole->state().dump());

  const auto refused_at = [&](json state) -> std::string {
    auto o = pareto_bat(6, 8, 11, s);
    try {
      o->restore(state);
    } catch (const InputError& e) {
      return e.errors().at(0).path;
    }
    return "";
  };
  EXPECT_EQ(refused_at(text), "");
  json other = text;
  other["objectives"] = 3;
  EXPECT_EQ(refused_at(other), "/objectives");
  ASSERT_GE(text["archive"].size(), 2u);
  json dominated = text;  // a second copy of a member's goals
  dominated["archive"][1]["f"] = dominated["archive"][0]["f"];
  EXPECT_EQ(refused_at(dominated), "/archive/1/f");
  json infeasible = text;
  infeasible["archive"][0]["f"]["violation"] = 0.5;
  EXPECT_EQ(refused_at(infeasible), "/archive/0/f");
  json bats = text;
  bats["bats"].erase(0);
  EXPECT_EQ(refused_at(bats), "/bats");
  json bad = text;
  bad["bats"][2]["f"]["violation"] = -1;
  EXPECT_EQ(refused_at(bad), "/bats/2/f/violation");
  json bat_state = text;
  bat_state["algorithm"] = "bat";
  EXPECT_NE(refused_at(bat_state), "x");  // refused (the common part names no field)
  EXPECT_THROW(pareto_bat(6, 8, 11, s)->restore(bat_state), InputError);
}

TEST(ParetoBatAlgorithm, WithoutAFeasiblePointTheLeadersAreThePopulationsLeastViolation) {
  // Every point of [-5, 5] violates, by 10 - x: no archive, and the bats follow the
  // population's first front (the least violation) toward x = 5. (This path once iterated over
  // a destroyed temporary; AddressSanitizer guards it here.)
  const SearchSpace s = box(1, -5, 5);
  FunctionObjectives f(2, [](const Decision& x) {
    return ObjectiveVector{{1 + x[0] * x[0], 1 + (x[0] - 2) * (x[0] - 2)}, 10 - x[0]};
  });
  auto opt = pareto_bat(6, 10, 5, s);
  const OptimizationResult r = run_optimizer(*opt, f);
  const auto& pb = dynamic_cast<const ParetoBatAlgorithm&>(*opt);
  EXPECT_TRUE(pb.archive().empty());
  EXPECT_EQ(r.evaluations, 66);
  EXPECT_GT(r.best[0], 4.0);
  EXPECT_LT(r.best_fitness, 0.0);  // constrained_fitness of an infeasible point
}

TEST(ParetoBatAlgorithm, OneObjectiveRunsOfBatAreTheBatAlgorithm) {
  // The registry's "bat" makes the Bat algorithm for one objective, unchanged.
  const SearchSpace s = box(2, -5, 5);
  auto one = bat(5, 3)->make(7, s);
  EXPECT_NE(dynamic_cast<BatAlgorithm*>(one.get()), nullptr);
  auto front = bat(5, 3)->make_front(7, s, 2);
  EXPECT_NE(dynamic_cast<ParetoBatAlgorithm*>(front.get()), nullptr);
  EXPECT_EQ(bat(5, 3)->to_json(), make_algorithm({{"type", "bat"}, {"population", 5},
                                                  {"iterations", 3}})->to_json());
}
