#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "cli_runner.hpp"
#include "ftc/tune/evaluators/tbb_evaluator.hpp"
#include "ftc/tune/job/job.hpp"
#include "ftc/tune/optimizers/bat.hpp"
#include "ftc/tune/optimizers/optimizer.hpp"
#include "ftc/tune/optimizers/pagmo.hpp"
#include "ftc/tune/run/documents.hpp"
#include "ftc/tune/run/tuning_run.hpp"
#include "short_job.hpp"
#include "test_functions.hpp"

using nlohmann::json;
using namespace ftc;
using namespace ftc::tune;
using namespace ftc::testing;

namespace {

AlgorithmPtr pagmo(const std::string& name, int population, int generations,
                   const json& settings = json::object()) {
  return make_algorithm({{"type", "pagmo"},
                         {"name", name},
                         {"population", population},
                         {"generations", generations},
                         {"settings", settings}});
}

// The algorithms of one objective (the multi-objective ones are tested below).
std::vector<std::string> all_names() {
  std::vector<std::string> names;
  for (const PagmoAlgorithmInfo& a : pagmo_algorithms())
    if (!a.front) names.push_back(a.name);
  return names;
}

// The smallest population every algorithm takes with its default settings (gaco: ker 63).
int population_for(const std::string& name) {
  return std::max(10, find_pagmo_algorithm(name)->min_population);
}

// A job's problems, joined one per line.
std::string problems(const json& algorithm) {
  json j = ftc::testing::short_table1_job();
  j["tuning"]["algorithm"] = algorithm;
  try {
    parse_job(j, "job");
  } catch (const InputError& e) {
    std::string s;
    for (const FieldError& f : e.errors()) s += to_string(f) + "\n";
    return s;
  }
  return "";
}

Job short_pagmo_job(const std::string& name, int population, int generations) {
  json j = ftc::testing::short_table1_job();
  j["tuning"]["algorithm"] = {
      {"type", "pagmo"}, {"name", name}, {"population", population}, {"generations", generations}};
  return parse_job(j, "short");
}

std::string gains(const Job& job, int threads, const RunOptions& o = {}) {
  TbbEvaluator evaluator(threads);
  return gains_document(tune::tune(job, evaluator, o)).dump();
}

}  // namespace

// Tolerances: the worst of seeds 1–10 measured with this adapter (population 30, 100
// generations, so 3 030 evaluations), rounded up to the next power of ten or a round number.
TEST(PagmoOptimizer, CmaesAndPsoGenSolveSphereInTwoToFiveDimensions) {
  for (const std::string name : {"cmaes", "pso_gen"}) {
    const double tolerance = name == "cmaes" ? 1e-6 : 1e-4;  // worst 9.9e-8 and 3.4e-5
    for (std::size_t d = 2; d <= 5; ++d)
      for (std::uint64_t seed = 1; seed <= 10; ++seed) {
        const OptimizationResult r = solve(pagmo(name, 30, 100), seed, box(d, -5, 5), sphere);
        EXPECT_LT(sphere(r.best), tolerance) << name << ", d = " << d << ", seed " << seed;
        EXPECT_DOUBLE_EQ(r.best_fitness, 1.0 / (1.0 + sphere(r.best)));
        for (std::size_t i = 1; i < r.history.size(); ++i)
          ASSERT_GE(r.history[i].best_fitness, r.history[i - 1].best_fitness);
      }
  }
}

TEST(PagmoOptimizer, CmaesAndPsoGenGetCloseOnRosenbrock) {
  // Worst over seeds 1–10 per dimension 2..5: CMA-ES 1.3e-8, 2.3e-8, 1.1e-6, 7.8e-4; PSO
  // 0.0030, 0.31, 1.21, 2.09 (its 3 030 evaluations do not get down the curved valley).
  const double cmaes[] = {1e-6, 1e-6, 1e-5, 1e-2};
  const double pso[] = {0.01, 0.5, 2.0, 3.0};
  for (std::size_t d = 2; d <= 5; ++d)
    for (std::uint64_t seed = 1; seed <= 10; ++seed) {
      const SearchSpace s = box(d, -2, 2);
      EXPECT_LT(rosenbrock(solve(pagmo("cmaes", 30, 100), seed, s, rosenbrock).best), cmaes[d - 2])
          << "d = " << d << ", seed " << seed;
      EXPECT_LT(rosenbrock(solve(pagmo("pso_gen", 30, 100), seed, s, rosenbrock).best), pso[d - 2])
          << "d = " << d << ", seed " << seed;
    }
}

TEST(PagmoOptimizer, EveryAlgorithmSpendsTheBudgetItDeclares) {
  for (const std::string& name : all_names()) {
    const AlgorithmPtr a = pagmo(name, population_for(name), 6);
    CheckingEvaluator seen(box(3, -5, 5), sphere);
    const OptimizationResult r = solve(a, 3, box(3, -5, 5), sphere, &seen);
    // Six generations are too few for any stopping tolerance on this sphere, so the run spends
    // exactly what the settings declare.
    EXPECT_EQ(r.evaluations, a->evaluations()) << name;
    ASSERT_EQ(r.history.size(), 7u) << name;
    const PagmoAlgorithmInfo& info = *find_pagmo_algorithm(name);
    for (std::size_t g = 0; g < r.history.size(); ++g)
      EXPECT_EQ(r.history[g].evaluations,
                a->population() +
                    static_cast<std::int64_t>(g) * (a->population() * info.per_member + info.fixed))
          << name << ", generation " << g;
  }
  EXPECT_EQ(pagmo("bee_colony", 10, 5)->evaluations(), 10 + 5 * 20);
  EXPECT_EQ(pagmo("sea", 10, 100)->evaluations(), 10 + 100);
}

TEST(PagmoOptimizer, StoppingToleranceEndsTheRunEarlyAndCountsWhatItSpent) {
  // CMA-ES on a 2-D sphere meets ftol = 1e-6 long before 100 generations.
  const AlgorithmPtr a = pagmo("cmaes", 30, 100);
  const OptimizationResult r = solve(a, 1, box(2, -5, 5), sphere);
  EXPECT_TRUE(r.completed);
  EXPECT_LT(r.evaluations, a->evaluations());
  EXPECT_EQ(r.history.size(), 101u);
  EXPECT_EQ(r.history.back().evaluations, r.history[r.history.size() - 2].evaluations);
}

// The run says so when the algorithm stops evaluating before its generations end, and its ETA
// then counts only the comparison and the noise floor: a CMA-ES run stood at "240/732 evaluations, ETA 4.0 s" for 41 iterations without a word
// (issue 41: "ends at 120/132 evaluations although validate said 132").
TEST(PagmoTuning, ARunSaysWhenTheAlgorithmsOwnStoppingRuleEndsItsEvaluations) {
  const auto dir = ftc::testing::fresh_dir("pagmo-stalls");
  json j = ftc::testing::short_table1_job();
  j["tuning"]["algorithm"] = {
      {"type", "pagmo"}, {"name", "cmaes"}, {"population", 12}, {"generations", 60}};
  std::ofstream(dir / "job.json") << j.dump();
  const ftc::testing::CliResult r = ftc::testing::run_cli(
      "run '" + (dir / "job.json").string() + "' --out '" + (dir / "out").string() + "'", dir);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::size_t said = r.err.find(": cmaes evaluated no candidate: it met its own stopping rule");
  ASSERT_NE(said, std::string::npos) << r.err;
  EXPECT_EQ(r.err.find("evaluated no candidate", said + 30), std::string::npos);  // said once
  EXPECT_NE(r.err.find("of the 732 evaluations its generations allow"), std::string::npos);
  // Every iteration after it counts only what the run evaluates after its iterations in its
  // ETA: the comparison of 4 controllers and 8 noise-floor reruns, 12 evaluations against the
  // 240 done (it counted the 492 the stopped generations would have made).
  int after = 0;
  for (std::size_t at = r.err.find(" s elapsed, ETA ", said); at != std::string::npos;
       at = r.err.find(" s elapsed, ETA ", at + 1)) {
    const std::size_t from = r.err.rfind(", ", at) + 2;
    double elapsed = -1, eta = -1;
    ASSERT_EQ(std::sscanf(r.err.c_str() + from, "%lf s elapsed, ETA %lf s", &elapsed, &eta), 2)
        << r.err.substr(from, 40);
    EXPECT_LE(eta, elapsed * 12.0 / 240.0 + 0.051) << r.err.substr(from, 40);
    ++after;
  }
  EXPECT_GT(after, 30);
}

TEST(PagmoOptimizer, BatchAlgorithmsEvaluateAGenerationInOneBatch) {
  for (const auto& [name, population] :
       std::vector<std::pair<std::string, int>>{{"pso_gen", 8}, {"gaco", 63}}) {
    CheckingEvaluator seen(box(2, -5, 5), sphere);
    solve(pagmo(name, population, 4), 1, box(2, -5, 5), sphere, &seen);
    EXPECT_EQ(seen.batches, std::vector<std::size_t>(5, population)) << name;
    EXPECT_TRUE(find_pagmo_algorithm(name)->batch);
  }
  // The others ask for one candidate at a time; only their initial population is one batch.
  CheckingEvaluator seen(box(2, -5, 5), sphere);
  solve(pagmo("cmaes", 8, 4), 1, box(2, -5, 5), sphere, &seen);
  std::vector<std::size_t> expected{8};
  expected.resize(1 + 4 * 8, 1);
  EXPECT_EQ(seen.batches, expected);
  EXPECT_FALSE(find_pagmo_algorithm("cmaes")->batch);
}

TEST(PagmoOptimizer, DivergedCandidatesArePenalisedNotFatal) {
  // Half the box "diverges" (J = 0): the run goes on and ends on the other half.
  static constexpr auto half = [](const Decision& x) { return x[0] < 0 ? -1.0 : sphere(x); };
  class HalfFitness final : public BatchFitness {
   public:
    std::vector<double> operator()(const std::vector<Decision>& batch) override {
      std::vector<double> J;
      for (const Decision& x : batch) {
        const double f = half(x);
        J.push_back(f < 0 ? 0.0 : 1.0 / (1.0 + f));
      }
      return J;
    }
  } fitness;
  for (const std::string name : {"cmaes", "pso_gen", "bee_colony", "sade"}) {
    auto opt = pagmo(name, 10, 20)->make(1, box(2, -5, 5));
    const OptimizationResult r = run_optimizer(*opt, fitness);
    EXPECT_TRUE(r.completed) << name;
    EXPECT_GE(r.best[0], 0.0) << name;
    EXPECT_GT(r.best_fitness, 0.5) << name;
    double diverged = 0;
    for (const HistoryRow& h : r.history)
      for (const auto& [column, value] : h.extras)
        if (column == "generation_diverged") diverged += value;
    EXPECT_GT(diverged, 0) << name << ": no candidate diverged, the test proves nothing";
  }
}

TEST(PagmoOptimizer, SameSeedSameRunOtherSeedOtherRun) {
  const AlgorithmPtr a = pagmo("pso_gen", 10, 5);
  const SearchSpace s = box(3, -5, 5);
  const OptimizationResult one = solve(a, 4, s, rosenbrock), two = solve(a, 4, s, rosenbrock);
  const OptimizationResult other = solve(a, 5, s, rosenbrock);
  ASSERT_EQ(one.history.size(), two.history.size());
  for (std::size_t i = 0; i < one.history.size(); ++i)
    EXPECT_EQ(one.history[i].best, two.history[i].best);
  EXPECT_NE(one.history.front().best, other.history.front().best);
}

TEST(PagmoOptimizer, ResumeFromSavedStateContinuesExactlyForEveryAlgorithm) {
  for (const std::string& name : all_names()) {
    const AlgorithmPtr a = pagmo(name, population_for(name), 6);
    const SearchSpace s = box(3, -2, 2);
    CheckingEvaluator fitness(s, rosenbrock);
    auto full = a->make(11, s);
    const OptimizationResult uninterrupted = run_optimizer(*full, fitness);

    std::string saved;
    auto first = a->make(11, s);
    run_optimizer(*first, fitness, [&](const HistoryRow& h, const Optimizer& o) {
      saved = o.state().dump();  // through text, as a checkpoint store keeps it
      return h.iteration < 3;
    });
    const json state = json::parse(saved);
    CheckingEvaluator after(s, rosenbrock);
    auto second = a->make(999, s);  // the seed must not matter: the state has the run
    const OptimizationResult resumed = run_optimizer(*second, after, {}, &state);
    ASSERT_EQ(resumed.history.size(), uninterrupted.history.size()) << name;
    for (std::size_t i = 0; i < resumed.history.size(); ++i) {
      EXPECT_EQ(resumed.history[i].best, uninterrupted.history[i].best) << name << ", " << i;
      EXPECT_EQ(resumed.history[i].best_fitness, uninterrupted.history[i].best_fitness);
      EXPECT_EQ(resumed.history[i].evaluations, uninterrupted.history[i].evaluations);
    }
    EXPECT_TRUE(resumed.completed);
    // Nothing logged is simulated again.
    EXPECT_EQ(after.evaluations, uninterrupted.evaluations - resumed.history[3].evaluations)
        << name;
  }
}

TEST(PagmoOptimizer, RejectsCheckpointsOfOtherRunsAndDamagedOnes) {
  const SearchSpace s = box(2, -5, 5);
  CheckingEvaluator fitness(s, sphere);
  const auto state_of = [&](const AlgorithmPtr& a, std::uint64_t seed,
                            const SearchSpace& space = box(2, -5, 5)) {
    auto o = a->make(seed, space);
    run_optimizer(*o, fitness,
                  [](const HistoryRow& h, const Optimizer&) { return h.iteration < 2; });
    return o->state();
  };
  const auto rejected = [&](const AlgorithmPtr& a, const json& state, const std::string& what) {
    auto o = a->make(1, s);
    try {
      o->restore(state);
    } catch (const InputError& e) {
      EXPECT_EQ(e.source(), "checkpoint");
      EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
      return;
    }
    ADD_FAILURE() << "accepted a checkpoint it should refuse (" << what << ")";
  };
  const AlgorithmPtr pso = pagmo("pso_gen", 6, 5);
  const json good = state_of(pso, 1);
  {
    auto o = pso->make(1, s);
    EXPECT_NO_THROW(o->restore(good));
  }
  rejected(pso, state_of(make_algorithm({{"type", "bat"}, {"population", 6}}), 1), "pagmo");
  rejected(pso, state_of(pagmo("cmaes", 6, 5), 1), "cmaes");
  rejected(pso, state_of(pso, 1, box(2, -4, 4)), "does not replay");  // another problem
  json damaged = good;
  damaged["fitness_log"][7] = 0.5;
  rejected(pso, damaged, "does not replay");
  json short_log = good;
  short_log["fitness_log"].erase(short_log["fitness_log"].size() - 1);
  rejected(pso, short_log, "/fitness_log: holds");
  // Forged states (a forger recomputes the checkpoint's digest): every field is checked.
  for (const json& t : {json(6), json(61), json(1e9), json(-1)}) {
    json forged = good;
    forged["t"] = t;
    rejected(pso, forged, "/t: expected an integer in [0, 5]");
  }
  json forged = good;
  forged["evaluations"] = 1e18;
  rejected(pso, forged, "/evaluations: expected an integer in [0, 36]");
  forged = good;
  forged["rng"] = "garbage";
  rejected(pso, forged, "/rng: is not the state of the random engine");
  forged = good;
  forged["best"] = json::array({1.0});
  rejected(pso, forged, "/best: holds 1 elements, expected 2");
  forged = good;
  forged["pagmo_seeds"][0] = -1;
  rejected(pso, forged, "/pagmo_seeds/0");
  forged = good;
  forged["pagmo_seeds"] = json::array({1});
  rejected(pso, forged, "/pagmo_seeds: holds 1 elements");
  forged = good;
  forged["finished"] = "no";
  rejected(pso, forged, "/finished");
  forged = good;
  forged["fitness_log"][3] = "x";
  rejected(pso, forged, "/fitness_log/3");
  // No run gives a fitness below -1 (an infeasible candidate's -V/(1+V)). Every objective of
  // bee_colony's replay infinite made its onlooker loop spin for ever: refused before the replay.
  const AlgorithmPtr bees = pagmo("bee_colony", 6, 3);
  json hive = state_of(bees, 1);
  for (json& f : hive["fitness_log"]) f = -1e300;
  rejected(bees, hive, "/fitness_log/0: expected a number in [-1, ");
}

TEST(PagmoSettings, ErrorsNameTheirJsonPath) {
  const json ok = {{"type", "pagmo"}, {"name", "pso_gen"}, {"population", 10}};
  EXPECT_EQ(problems(ok), "");
  json j = ok;
  j["name"] = "pso2";
  EXPECT_EQ(problems(j),
            "/tuning/algorithm/name: unknown pagmo algorithm \"pso2\" (known: bee_colony, cmaes, "
            "de, de1220, gaco, gwo, ihs, maco, moead, nsga2, nspso, pso, pso_gen, sade, sea, sga, "
            "xnes)\n");
  j = ok;
  j["settings"] = {{"omegaa", 0.5}};
  EXPECT_NE(problems(j).find("/tuning/algorithm/settings/omegaa: unknown key (allowed here: "),
            std::string::npos)
      << problems(j);
  j["settings"] = {{"omega", "0.5"}, {"variant", 2.5}};
  EXPECT_EQ(problems(j),
            "/tuning/algorithm/settings/omega: expected a number, got a string\n"
            "/tuning/algorithm/settings/variant: expected an integer, got a number\n");
  j["settings"] = {{"omega", 1.5}};
  EXPECT_EQ(problems(j), "/tuning/algorithm/settings/omega: must be in [0, 1] (got 1.5)\n");
  // The adaptive random topology draws neighb_param - 1 informants per particle, again and
  // again: no more than the swarm (2e9 allocated tens of GB).
  j = ok;
  j["settings"] = {{"neighb_type", 4}, {"neighb_param", 2000000000}};
  EXPECT_EQ(problems(j),
            "/tuning/algorithm/settings/neighb_param: must be at most the population (10) for the "
            "adaptive random topology, got 2000000000\n");
  j["settings"]["neighb_param"] = 10;
  EXPECT_EQ(problems(j), "");
  j = ok;
  j["iterations"] = 10;  // the Bat algorithm's word; pagmo's is generations
  EXPECT_NE(problems(j).find("/tuning/algorithm/iterations: unknown key"), std::string::npos);
  EXPECT_EQ(problems({{"type", "pagmo"}, {"name", "cmaes"}, {"population", 3}}),
            "/tuning/algorithm/population: must be at least 5 for cmaes (got 3)\n");
  // An unknown setting does not hide the population that is too small: both are reported.
  const std::string both = problems(
      {{"type", "pagmo"}, {"name", "cmaes"}, {"population", 3}, {"settings", {{"sigma", 0.3}}}});
  EXPECT_NE(both.find("/tuning/algorithm/settings/sigma: unknown key"), std::string::npos) << both;
  EXPECT_NE(both.find("/tuning/algorithm/population: must be at least 5 for cmaes (got 3)\n"),
            std::string::npos)
      << both;
  EXPECT_EQ(problems({{"type", "pagmo"}, {"name", "gaco"}, {"population", 10}}),
            "/tuning/algorithm/population: must be at least 63 for gaco with ker 63 (got 10)\n");
  EXPECT_EQ(problems({{"type", "pagmo"},
                      {"name", "gaco"},
                      {"population", 10},
                      {"settings", {{"ker", 8}, {"threshold", 20}}}}),
            "/tuning/algorithm/settings/threshold: must be at most generations 10 (got 20)\n");
  EXPECT_EQ(problems({{"type", "pagmo"},
                      {"name", "sga"},
                      {"population", 9},
                      {"settings", {{"crossover", "sbx"}}}}),
            "/tuning/algorithm/population: must be even for sbx crossover (got 9)\n");
  EXPECT_EQ(problems({{"type", "pagmo"}, {"name", "sea"}, {"settings", {{"gen", 3}}}}),
            "/tuning/algorithm/settings/gen: sea has no settings\n");
  EXPECT_EQ(problems({{"type", "pagmo"}, {"name", "cmaes"}, {"settings", {{"cc", 2}}}}),
            "/tuning/algorithm/settings/cc: must be -1 (automatic) or in [0, 1] (got 2)\n");
  EXPECT_EQ(problems({{"type", "pagmo"}}),
            "/tuning/algorithm/name: is required (one of bee_colony, cmaes, de, de1220, gaco, "
            "gwo, ihs, maco, moead, nsga2, nspso, pso, pso_gen, sade, sea, sga, xnes)\n");
}

TEST(PagmoSettings, ResolvedFormHasPagmosDefaultsAndRoundTrips) {
  const AlgorithmPtr a = pagmo("pso_gen", 12, 7, {{"omega", 0.5}});
  const json j = a->to_json();
  EXPECT_EQ(j["type"], "pagmo");
  EXPECT_EQ(j["name"], "pso_gen");
  EXPECT_EQ(j["population"], 12);
  EXPECT_EQ(j["generations"], 7);
  EXPECT_EQ(j["settings"], json({{"omega", 0.5},
                                 {"eta1", 2.05},
                                 {"eta2", 2.05},
                                 {"max_vel", 0.5},
                                 {"variant", 5},
                                 {"neighb_type", 2},
                                 {"neighb_param", 4}}));
  EXPECT_EQ(make_algorithm(j)->to_json().dump(), j.dump());
  EXPECT_EQ(a->evaluations(), 12 + 7 * 12);
  EXPECT_EQ(a->iterations(), 7);
  EXPECT_EQ(a->history_columns(),
            (std::vector<std::string>{"generation_mean_objective", "generation_diverged"}));
}

TEST(PagmoSettings, SchemaHasOneCasePerAlgorithmListingItsSettings) {
  const json s = find_algorithm("pagmo")->schema();
  ASSERT_EQ(s["oneOf"].size(), pagmo_algorithms().size());
  for (const json& c : s["oneOf"]) {
    const std::string name = c["properties"]["name"]["const"];
    EXPECT_EQ(c["properties"]["type"]["const"], "pagmo");
    EXPECT_EQ(c["additionalProperties"], false);
    const json& settings = c["properties"]["settings"];
    EXPECT_EQ(settings["additionalProperties"], false) << name;
    if (name == "pso_gen") {
      for (const char* k :
           {"omega", "eta1", "eta2", "max_vel", "variant", "neighb_type", "neighb_param"})
        EXPECT_TRUE(settings["properties"].contains(k)) << k;
      EXPECT_EQ(settings["properties"]["omega"]["default"], 0.7298);
    }
    if (name == "cmaes") {
      EXPECT_EQ(settings["properties"]["sigma0"]["default"], 0.5);
    }
  }
}

TEST(PagmoSettings, WithBudgetFitsWholeGenerations) {
  EXPECT_EQ(pagmo("bee_colony", 10, 1)->with_budget(110)->iterations(), 5);
  EXPECT_EQ(pagmo("sea", 10, 1)->with_budget(110)->iterations(), 100);
  EXPECT_EQ(pagmo("cmaes", 10, 1)->with_budget(1000)->iterations(), 99);
  EXPECT_EQ(pagmo("cmaes", 10, 1)->with_budget(1000)->evaluations(), 1000);
  EXPECT_EQ(pagmo("bee_colony", 10, 1)->with_budget(1000)->evaluations(), 990);
  EXPECT_EQ(pagmo("cmaes", 10, 1)->with_budget(19), nullptr);  // not one generation
  EXPECT_EQ(pagmo("gaco", 63, 1)->with_budget(110), nullptr);
  const AlgorithmPtr bat = make_algorithm({{"type", "bat"}, {"population", 10}});
  EXPECT_EQ(bat->with_budget(110)->iterations(), 10);
  EXPECT_EQ(bat->with_budget(119)->evaluations(), 110);
  EXPECT_EQ(bat->with_budget(19), nullptr);
}

TEST(PagmoTuning, GainsIdenticalForOneAndTwoThreads) {
  for (const std::string name : {"pso_gen", "cmaes"}) {
    const Job job = short_pagmo_job(name, 5, 2);
    const std::string one = gains(job, 1);
    EXPECT_EQ(one, gains(job, 2)) << name;
    const json g = json::parse(one);
    EXPECT_EQ(g["optimizer"]["type"], "pagmo");
    EXPECT_EQ(g["optimizer"]["name"], name);
    EXPECT_EQ(g["optimizer"]["evaluations"], 15);
  }
}

TEST(PagmoTuning, ResumedRunGivesTheSameGainsFile) {
  const Job job = short_pagmo_job("pso_gen", 5, 3);
  const std::string uninterrupted = gains(job, 2);
  std::string checkpoint;
  RunOptions stop;
  stop.observer = [&](const HistoryRow& h, const Optimizer& o, const std::vector<Trial>& trials) {
    checkpoint = run_checkpoint(o, trials).dump();
    return h.iteration < 1;
  };
  TbbEvaluator one(1);
  EXPECT_FALSE(tune::tune(job, one, stop).completed());
  const json state = json::parse(checkpoint);
  RunOptions resume;
  resume.resume = &state;
  EXPECT_EQ(gains(job, 2, resume), uninterrupted);
}

namespace {
// How many times the dynamic loader mentions libpagmo while the CLI runs `args`.
int libpagmo_mentions(const std::string& args) {
  const std::string cmd = "cd '" FTC_SOURCE_DIR "' && LD_DEBUG=libs '" FTC_CLI "' " + args +
                          " 2>&1 >/dev/null | grep -c 'libpagmo'";
  FILE* p = ::popen(cmd.c_str(), "r");
  if (!p) return -1;
  int n = -1;
  if (std::fscanf(p, "%d", &n) != 1) n = -1;
  ::pclose(p);
  return n;
}
}  // namespace

TEST(Pagmo, LibraryIsLoadedOnlyWhenAJobNamesAPagmoAlgorithm) {
  // Its static initialisers cost ~60 ms and 36 MB: `--version`, `validate` and a Bat run skip it.
  EXPECT_EQ(libpagmo_mentions("--version"), 0);
  EXPECT_EQ(libpagmo_mentions("validate jobs/table1.json"), 0);
  const auto dir = ftc::testing::fresh_dir("pagmo-lazy");
  json j = ftc::testing::short_table1_job();
  j["tuning"]["algorithm"] = {
      {"type", "pagmo"}, {"name", "sea"}, {"population", 4}, {"generations", 2}};
  std::ofstream(dir / "job.json") << j.dump();
  EXPECT_GT(libpagmo_mentions("validate '" + (dir / "job.json").string() + "'"), 0);
  // ... and the module loads and parses it.
  const ftc::testing::CliResult r =
      ftc::testing::run_cli("validate '" + (dir / "job.json").string() + "'", dir);
  EXPECT_EQ(r.exit_code, 0) << r.err;
}

// ---- pagmo's multi-objective algorithms (issue 26) --------------------------------------------

namespace {

const char* kFrontAlgorithms[] = {"nsga2", "moead", "nspso", "maco"};

// Settings that fit a population of 8 (MOEA/D's neighbourhood, MHACO's archive).
json front_settings(const std::string& name) {
  if (name == "moead") return {{"neighbours", 4}};
  if (name == "maco") return {{"ker", 4}};
  return json::object();
}

// ZDT1 on two variables in [0, 1]: f1 = x0, f2 = g·(1 − sqrt(x0/g)), g = 1 + 9·x1; its front is
// x1 = 0. With `limit`, the hard goal x0 >= limit (violation (limit − x0)/limit where broken).
struct Zdt1 {
  double limit = 0;
  std::vector<std::pair<Decision, ObjectiveVector>> seen;
  ObjectiveVector operator()(const Decision& x) {
    const double g = 1 + 9 * x[1];
    ObjectiveVector o{{x[0], g * (1 - std::sqrt(x[0] / g))}, 0.0};
    if (x[0] < limit) o.violation = (limit - x[0]) / limit;
    seen.emplace_back(x, o);
    return o;
  }
};

// The hypervolume of the feasible points against (1.1, 11), by a sweep over f1.
double hypervolume2(std::vector<ObjectiveVector> points) {
  std::vector<std::pair<double, double>> p;
  for (const ObjectiveVector& o : points)
    if (o.feasible() && o.values[0] < 1.1 && o.values[1] < 11) p.emplace_back(o.values[0], o.values[1]);
  std::sort(p.begin(), p.end());
  double hv = 0, best2 = 11;
  for (std::size_t i = 0; i < p.size(); ++i) {
    best2 = std::min(best2, p[i].second);
    const double next = i + 1 < p.size() ? p[i + 1].first : 1.1;
    hv += (next - p[i].first) * (11 - best2);
  }
  return hv;
}

OptimizationResult solve_front(const AlgorithmPtr& a, std::uint64_t seed, Zdt1& zdt) {
  FunctionObjectives fitness(2, [&](const Decision& x) { return zdt(x); });
  const std::unique_ptr<Optimizer> o = a->make_front(seed, box(2, 0, 1), 2);
  return run_optimizer(*o, fitness);
}

}  // namespace

// Each algorithm spends what it declares, improves on its initial population's front, and
// reports as its best point the evaluated feasible point of least first goal.
TEST(PagmoFront, EveryAlgorithmSpendsItsBudgetImprovesItsFrontAndReportsItsBest) {
  for (const std::string name : kFrontAlgorithms) {
    const AlgorithmPtr a = pagmo(name, 8, 10, front_settings(name));
    ASSERT_TRUE(a->searches_front()) << name;
    Zdt1 zdt;
    const OptimizationResult r = solve_front(a, 3, zdt);
    EXPECT_EQ(r.evaluations, a->evaluations()) << name;
    ASSERT_EQ(r.history.size(), 11u) << name;
    ASSERT_EQ(zdt.seen.size(), static_cast<std::size_t>(r.evaluations)) << name;
    std::vector<ObjectiveVector> initial, all;
    for (std::size_t i = 0; i < zdt.seen.size(); ++i) {
      all.push_back(zdt.seen[i].second);
      if (i < 8) initial.push_back(zdt.seen[i].second);
    }
    EXPECT_GT(hypervolume2(all), hypervolume2(initial)) << name;
    const auto least = std::min_element(zdt.seen.begin(), zdt.seen.end(), [](auto& p, auto& q) {
      return p.second.values[0] < q.second.values[0];
    });
    EXPECT_EQ(r.best, least->first) << name;
    EXPECT_EQ(r.best_fitness, 1.0 / least->second.values[0]) << name;
  }
}

// Hard goals reach pagmo as constrained domination: NSGA-II's population becomes feasible, and the
// best point is a feasible one.
TEST(PagmoFront, HardGoalsAreConstrainedDomination) {
  for (const std::string name : kFrontAlgorithms) {
    const AlgorithmPtr a = pagmo(name, 8, 10, front_settings(name));
    Zdt1 zdt;
    zdt.limit = 0.5;
    const OptimizationResult r = solve_front(a, 5, zdt);
    EXPECT_GE(r.best[0], 0.5) << name;
    EXPECT_GT(r.best_fitness, 0) << name;  // feasible: J = 1/f1
    const auto feasible = [](const HistoryRow& h) {
      for (const auto& [k, v] : h.extras)
        if (k == "generation_feasible") return v;
      return -1.0;
    };
    if (name == "nsga2") {
      EXPECT_LT(feasible(r.history.front()), 8) << name;
      EXPECT_EQ(feasible(r.history.back()), 8) << name;
    }
  }
}

TEST(PagmoFront, ResumeFromSavedStateContinuesExactlyForEveryAlgorithm) {
  for (const std::string name : kFrontAlgorithms) {
    const AlgorithmPtr a = pagmo(name, 8, 6, front_settings(name));
    Zdt1 full_zdt;
    const OptimizationResult uninterrupted = solve_front(a, 11, full_zdt);
    std::string saved;
    Zdt1 first_zdt;
    FunctionObjectives first_f(2, [&](const Decision& x) { return first_zdt(x); });
    auto first = a->make_front(11, box(2, 0, 1), 2);
    run_optimizer(*first, first_f, [&](const HistoryRow& h, const Optimizer& o) {
      saved = o.state().dump();
      return h.iteration < 3;
    });
    const json state = json::parse(saved);
    Zdt1 after_zdt;
    FunctionObjectives after_f(2, [&](const Decision& x) { return after_zdt(x); });
    auto second = a->make_front(999, box(2, 0, 1), 2);
    const OptimizationResult resumed = run_optimizer(*second, after_f, {}, &state);
    ASSERT_EQ(resumed.history.size(), uninterrupted.history.size()) << name;
    for (std::size_t i = 0; i < resumed.history.size(); ++i) {
      EXPECT_EQ(resumed.history[i].best, uninterrupted.history[i].best) << name << ", " << i;
      EXPECT_EQ(resumed.history[i].best_fitness, uninterrupted.history[i].best_fitness);
      EXPECT_EQ(resumed.history[i].evaluations, uninterrupted.history[i].evaluations);
    }
    EXPECT_EQ(static_cast<std::int64_t>(after_zdt.seen.size()),
              uninterrupted.evaluations - resumed.history[3].evaluations)
        << name;
    // A damaged log does not replay to the checkpoint's best: the first candidate's first goal
    // made 0, below every other, makes it the best point.
    json bad = state;
    bad["objective_log"][0][0] = 0.0;
    auto third = a->make_front(11, box(2, 0, 1), 2);
    EXPECT_THROW(run_optimizer(*third, after_f, {}, &bad), InputError) << name;
  }
}

// MOEA/D's grid weights: with three or more soft goals the population must be a size the grid
// has (C(H + M - 1, M - 1)); validate said yes to 22 for three goals and the run refused it.
// The rule is pagmo's: the sizes it refuses, pagmo refuses, and those it takes, pagmo runs.
TEST(PagmoFront, MoeadsGridWeightsNeedAPopulationTheGridHasAndValidateSaysSo) {
  const json settings = {{"neighbours", 4}};
  const auto errors = [&](int population, std::size_t objectives, const json& s) {
    std::string text;
    for (const FieldError& f :
         pagmo("moead", population, 1, s)->validate_front(objectives, "/tuning/algorithm"))
      text += to_string(f) + "\n";
    return text;
  };
  EXPECT_EQ(errors(22, 3, settings),
            "/tuning/algorithm/population: must be C(H + 2, 2) for some H with moead's grid "
            "weights and 3 soft goals, such as 21 or 28 (got 22); or set "
            "settings.weight_generation to \"low discrepancy\"\n");
  EXPECT_EQ(errors(21, 3, settings), "");
  EXPECT_EQ(errors(22, 2, settings), "");  // two goals: any size
  EXPECT_NE(errors(16, 4, settings).find("such as 10 or 20 (got 16)"), std::string::npos);
  EXPECT_EQ(errors(20, 4, settings), "");
  json low = settings;
  low["weight_generation"] = "low discrepancy";
  EXPECT_EQ(errors(22, 3, low), "");
  // pagmo agrees, on a problem of three objectives.
  for (const int population : {21, 22}) {
    FunctionObjectives fitness(3, [](const Decision& x) {
      return ObjectiveVector{{x[0], x[1], 2 - x[0] - x[1]}, 0.0};
    });
    const auto o = pagmo("moead", population, 1, settings)->make_front(3, box(2, 0, 1), 3);
    if (population == 21)
      EXPECT_NO_THROW(run_optimizer(*o, fitness));
    else
      EXPECT_ANY_THROW(run_optimizer(*o, fitness));
  }
  // The job: validate refuses it at the population's path, before any run.
  json j = short_table1_job();
  j.erase("objective");
  j["goals"] = {{{"metric", "ise"}, {"minimize", true}},
                {{"metric", "control_tv"}, {"minimize", true}},
                {{"metric", "peak_command"}, {"minimize", true}}};
  j["tuning"]["algorithm"] = {{"type", "pagmo"}, {"name", "moead"},     {"population", 22},
                              {"generations", 1}, {"settings", settings}};
  try {
    parse_job(j, "moead-22");
    ADD_FAILURE() << "a population of 22 was accepted";
  } catch (const InputError& e) {
    EXPECT_EQ(e.errors().at(0).path, "/tuning/algorithm/population") << e.what();
  }
  j["tuning"]["algorithm"]["population"] = 21;
  EXPECT_NO_THROW(parse_job(j, "moead-21"));
}

TEST(PagmoFront, SettingsAndSizesAreCheckedAtTheirPaths) {
  const auto errors = [](const json& algorithm) {
    std::vector<FieldError> e;
    parse_algorithm(algorithm, "/tuning/algorithm", e);
    std::string s;
    for (const FieldError& f : e) s += to_string(f) + "\n";
    return s;
  };
  const json base = {{"type", "pagmo"}, {"population", 8}, {"generations", 2}};
  json j = base;
  j["name"] = "nsga2";
  j["population"] = 10;
  EXPECT_NE(errors(j).find("/tuning/algorithm/population: must be a multiple of 4 and at least 8"),
            std::string::npos)
      << errors(j);
  j = base;
  j["name"] = "moead";
  EXPECT_NE(errors(j).find("/tuning/algorithm/population: must be at least 21 for moead with "
                           "neighbours 20"),
            std::string::npos)
      << errors(j);
  j = base;
  j["name"] = "maco";
  EXPECT_NE(errors(j).find("/tuning/algorithm/population: must be at least 63 for maco with ker 63"),
            std::string::npos)
      << errors(j);
  j = base;
  j["name"] = "nsga2";
  j["settings"] = {{"cr", 1.0}};
  EXPECT_NE(errors(j).find("/tuning/algorithm/settings/cr"), std::string::npos) << errors(j);
  j = base;
  j["name"] = "nspso";
  j["settings"] = {{"diversity_mechanism", "none"}};
  EXPECT_NE(errors(j).find("/tuning/algorithm/settings/diversity_mechanism"), std::string::npos)
      << errors(j);
  // A front's algorithm has nothing to do with one objective: the job is refused at the name
  // (and a run of it, should one be started, stops there too).
  EXPECT_EQ(problems({{"type", "pagmo"}, {"name", "nsga2"}, {"population", 8}}),
            "/tuning/algorithm/name: pagmo's nsga2 searches a Pareto front: give the job two or "
            "more soft goals (\"minimize\": true), or name an algorithm of one objective\n");
  const AlgorithmPtr a = pagmo("nsga2", 8, 2);
  EXPECT_THROW(a->make(1, box(2, 0, 1)), InputError);
  EXPECT_FALSE(pagmo("cmaes", 10, 2)->searches_front());
}

namespace {
Job two_goal_job(const std::string& name, int generations) {
  json j = tiny_job("front-" + name);
  j.erase("objective");
  j["goals"] = {{{"metric", "ise"}, {"window", {0, 0.05}}, {"minimize", true}},
                {{"metric", "control_tv"}, {"minimize", true}}};
  j["tuning"]["algorithm"] = {{"type", "pagmo"},
                              {"name", name},
                              {"population", 8},
                              {"generations", generations},
                              {"settings", front_settings(name)}};
  return parse_job(j, "front");
}
}  // namespace

// A checkpointed two-goal run resumes to the same files as the uninterrupted one.
TEST(PagmoTuning, ResumedTwoGoalRunGivesTheSameFiles) {
  for (const std::string name : {"nsga2", "moead"}) {
    const Job job = two_goal_job(name, 3);
    TbbEvaluator evaluator(2);
    const std::map<std::string, std::string> uninterrupted = output_files(tune::tune(job, evaluator));
    std::string checkpoint;
    RunOptions stop;
    stop.observer = [&](const HistoryRow& h, const Optimizer& o, const std::vector<Trial>& trials) {
      checkpoint = run_checkpoint(o, trials).dump();
      return h.iteration < 1;
    };
    EXPECT_FALSE(tune::tune(job, evaluator, stop).completed()) << name;
    const json state = json::parse(checkpoint);
    RunOptions resume;
    resume.resume = &state;
    const std::map<std::string, std::string> resumed =
        output_files(tune::tune(job, evaluator, resume));
    for (const auto& [file, text] : uninterrupted)
      EXPECT_EQ(resumed.at(file), text) << name << ": " << file;
  }
}

// A two-goal job (ISE and control TV) through the whole run with each multi-objective algorithm:
// every file byte-identical on 1 and 2 threads, the budget spent as declared, and a front of
// several trade-offs among its trials (front.json's points, where the run writes one, mutually
// non-dominated).
TEST(PagmoTuning, TwoGoalJobGivesTheSameFilesOnOneAndTwoThreadsAndAFront) {
  for (const std::string name : kFrontAlgorithms) {
    const Job job = two_goal_job(name, 2);
    TbbEvaluator one(1), two(2);
    const TuningOutcome r1 = tune::tune(job, one);
    const std::map<std::string, std::string> f1 = output_files(r1),
                                             f2 = output_files(tune::tune(job, two));
    ASSERT_EQ(f1.size(), f2.size()) << name;
    for (const auto& [file, text] : f1) EXPECT_EQ(text, f2.at(file)) << name << ": " << file;
    EXPECT_EQ(r1.trials.size(), 24u) << name;
    // The non-dominated feasible trials: more than one, so the search saw a trade-off.
    std::vector<const Trial*> front;
    const auto dominates = [](const Trial& a, const Trial& b) {
      return a.goals[0] <= b.goals[0] && a.goals[1] <= b.goals[1] &&
             (a.goals[0] < b.goals[0] || a.goals[1] < b.goals[1]);
    };
    for (const Trial& t : r1.trials) {
      bool dominated = !(t.violation == 0) || !std::isfinite(t.goals[0]) ||
                       !std::isfinite(t.goals[1]);
      for (const Trial& u : r1.trials) dominated = dominated || dominates(u, t);
      if (!dominated) front.push_back(&t);
    }
    EXPECT_GE(front.size(), 2u) << name;
    if (f1.count("front.json")) {
      const json points = json::parse(f1.at("front.json"))["points"];
      for (const json& p : points)
        for (const json& q : points)
          EXPECT_FALSE(p["goals"][0] <= q["goals"][0] && p["goals"][1] <= q["goals"][1] &&
                       p["goals"] != q["goals"])
              << name << ": " << p.dump() << " dominates " << q.dump();
    }
  }
}
