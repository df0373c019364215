#include <gtest/gtest.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>
#include <nlohmann/json.hpp>
#include <random>

#include "cli_runner.hpp"
#include "ftc/runtime/gains.hpp"
#include "ftc/sim/simulation.hpp"
#include "ftc/sim/spacecraft.hpp"
#include "ftc/tune/evaluators/tbb_evaluator.hpp"
#include "ftc/tune/job/ensemble.hpp"
#include "ftc/tune/problem/problem.hpp"
#include "ftc/tune/run/documents.hpp"
#include "ftc/tune/run/tuning_run.hpp"
#include "goal_job.hpp"
#include "peak_memory.hpp"
#include "short_job.hpp"

using nlohmann::json;
using namespace ftc;
using namespace ftc::testing;

TEST(TuningProblem, MapsDecisionOntoNamedFields) {
  json j = short_table1_job();
  j["tuning"]["parameters"] = {{"Ki", {0, 50}}, {"c2", {1, 20}}, {"Kp", {1, 50}}};
  const tune::TuningProblem p(tune::parse_job(j, "x"));
  ASSERT_EQ(p.space().names, (std::vector<std::string>{"c2", "Kp", "Ki"}));  // field-table order
  const sim::ControllerConfig c = p.controller_for(std::vector<double>{7.5, 3.0, 11.0});
  EXPECT_EQ(c.c2, 7.5);
  EXPECT_EQ(c.Kp, 3.0);
  EXPECT_EQ(c.Ki, 11.0);
  EXPECT_EQ(c.c1, 10.0);  // untouched
}

TEST(TuningProblem, WithoutTuningSectionHasNoDecisionButCannotBeTuned) {
  json j = short_table1_job();
  j.erase("tuning");
  const tune::TuningProblem p(tune::parse_job(j, "x"));
  EXPECT_EQ(p.space().dimension(), 0u);
  EXPECT_EQ(p.controller_for({}).Kp, p.job().controller.Kp);
  tune::SerialEvaluator serial;
  EXPECT_THROW(tune::tune(p.job(), serial), InputError);
}

TEST(TuningProblem, DivergingOrThrowingCandidateScoresZero) {
  const tune::TuningProblem p(short_job());
  tune::TbbEvaluator ev(2);
  sim::ControllerConfig good = p.job().controller;
  sim::ControllerConfig unstable = good;
  unstable.c2 = 1e5;  // far beyond what 1 ms sampling can stabilise
  sim::ControllerConfig invalid = good;
  invalid.Kp = -1;  // make_controller throws inside the task
  const std::vector<sim::ControllerConfig> candidates = {good, unstable, invalid};
  const auto out = p.evaluate(candidates, ev);
  EXPECT_GT(out[0].evaluation.fitness, 0.0);
  EXPECT_TRUE(out[1].evaluation.diverged);
  EXPECT_EQ(out[1].evaluation.fitness, 0.0);
  EXPECT_EQ(out[2].evaluation.fitness, 0.0);
  EXPECT_NE(out[2].error.find("Kp"), std::string::npos) << out[2].error;
}

// Embedding ftctune in another optimiser: objective(x) is the job's objective of the controller
// with the tuned fields set from x, the number `ftctune simulate --set` reports for those gains.
TEST(TuningProblem, ObjectiveOfXIsWhatSimulateReports) {
  const auto dir = fresh_dir("objective");
  const tune::TuningProblem p(short_job());
  const tune::TuningProblem copy = p;          // copyable: copies share the plant
  const std::vector<double> x = {7.25, 12.5};  // Kp, Ki
  const double obj = copy.objective(x);
  std::ofstream(dir / "job.json") << short_table1_job().dump();
  const CliResult r =
      run_cli("simulate '" + (dir / "job.json").string() + "' --set Kp=7.25 --set Ki=12.5 --out '" +
                  (dir / "sim").string() + "' -q",
              dir);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const json metrics = json::parse(slurp(dir / "sim" / "metrics.json"));
  EXPECT_EQ(obj, metrics["objective"].get<double>());

  // Checked before anything runs: the dimension, and each value against its bounds.
  EXPECT_THROW(p.objective(std::vector<double>{1.0}), InputError);
  try {
    p.objective(std::vector<double>{60.0, 12.5});
    FAIL() << "accepted Kp = 60 outside [1, 50]";
  } catch (const InputError& e) {
    EXPECT_EQ(e.errors().at(0).path, "/0");
    EXPECT_NE(e.errors().at(0).message.find("Kp = 60 is outside its bounds [1, 50]"),
              std::string::npos)
        << e.what();
  }
}

TEST(TuningProblem, DivergedObjectiveIsInfiniteOrThePenaltyAskedFor) {
  json j = short_table1_job();
  j["tuning"]["parameters"] = {{"c2", {1e3, 3e5}}};  // 3e5 diverges at 1 ms (see below)
  const tune::TuningProblem p(tune::parse_job(j, "x"));
  const std::vector<double> x = {3e5};
  EXPECT_TRUE(std::isinf(p.objective(x)));
  EXPECT_EQ(p.objective(x, {.diverged_penalty = 1e30}), 1e30);
  EXPECT_LT(p.objective(std::vector<double>{1e3}), 1e30);  // a finite one is left alone
}

TEST(TuningProblem, LogScaleParametersAreSearchedInLogSpaceWithinBounds) {
  json j = short_table1_job();
  j["tuning"]["parameters"] = {{"Kp", {1, 50}},
                               {"switching_gain", {{"bounds", {2, 200}}, {"scale", "log"}}}};
  const tune::TuningProblem p(tune::parse_job(j, "x"));
  // switching_gain comes before Kp in the field table; its coordinate is ln x.
  ASSERT_EQ(p.space().names, (std::vector<std::string>{"switching_gain", "Kp"}));
  EXPECT_EQ(p.space().lower[0], std::log(2.0));
  EXPECT_EQ(p.space().upper[0], std::log(200.0));
  EXPECT_EQ(p.space().lower[1], 1.0);  // linear: the value itself
  // The midpoint of the search interval is the geometric mean of the bounds.
  const tune::Decision mid =
      p.to_parameters(std::vector<double>{0.5 * (std::log(2.0) + std::log(200.0)), 25.5});
  EXPECT_NEAR(mid[0], 20.0, 1e-12);
  EXPECT_EQ(mid[1], 25.5);
  // exp(ln 200) may round above 200; the value stays inside the bounds all the same.
  for (const double y : {std::log(2.0), std::log(200.0)}) {
    const tune::Decision x = p.to_parameters(std::vector<double>{y, 1.0});
    EXPECT_GE(x[0], 2.0);
    EXPECT_LE(x[0], 200.0);
  }
  EXPECT_EQ(p.to_parameters(std::vector<double>{std::log(200.0), 1.0})[0], 200.0);
  EXPECT_EQ(p.controller_for(std::vector<double>{std::log(200.0), 7.0}).switching_gain, 200.0);
}

// Under model mismatch the loop simulates the true plant while the controller computes f(X)
// with its model. (Until 2026-11 the loop handed the controller the true plant's f, so that a
// mismatched run was bit for bit the run with a correct model: mismatch acted on nothing.)
TEST(TuningProblem, ModelMismatchSimulatesTheTruthAndControlsWithTheModel) {
  const tune::Job job = short_job();
  tune::Job mismatched = job;
  // The true plant; the model keeps 20, 17, 15.
  mismatched.scenarios[0].set_true_value("inertia", {22, 15.3, 16.5});
  tune::Job known = job;  // the same true plant, known to the controller
  known.plant.values = {22, 15.3, 16.5, 1.1e-3};
  const tune::TuningProblem nominal(job), off(mismatched), exact(known);
  const double ise = off.simulate(job.controller, 0).metrics.errors.ise;
  EXPECT_NE(ise, nominal.simulate(job.controller, 0).metrics.errors.ise);
  EXPECT_NE(ise, exact.simulate(job.controller, 0).metrics.errors.ise);
  // The same run through the generic loop: the true spacecraft, a controller built on the
  // model; the loop's f(X) is the truth's, so the controller must evaluate its own.
  sim::SpacecraftParams truth_params, model_params;
  truth_params.inertia = {22, 15.3, 16.5};
  const sim::Spacecraft truth(truth_params), model(model_params);
  auto controller = sim::make_controller(job.controller, model, job.scenarios[0].sample_time);
  sim::Scenario plain = mismatched.scenarios[0];
  plain.true_values.clear();
  const sim::SimulationResult by_hand =
      sim::simulate(truth, *controller, plain, off.simulation_options(0));
  EXPECT_NEAR(by_hand.metrics.errors.ise, ise, 1e-9 * ise);
  // Naming the plant's own inertia changes nothing.
  tune::Job same = job;
  same.scenarios[0].set_true_value("inertia", {20, 17, 15});
  EXPECT_EQ(tune::TuningProblem(same).simulate(job.controller, 0).metrics.errors.ise,
            nominal.simulate(job.controller, 0).metrics.errors.ise);
}

TEST(TuningProblem, UnrecoverableMembersAreFlaggedAndLeftOutUnlessIncluded) {
  json j = short_ensemble_job();
  j["ensemble"]["count"] = 12;
  j["ensemble"]["faults"]["count"] = {2, 2};
  j["ensemble"]["faults"]["type"] = {{"stuck", 1}};  // every member: two stuck actuators
  const tune::TuningProblem p(tune::parse_job(j, "x"));
  ASSERT_EQ(p.scenarios(), 13u);
  EXPECT_TRUE(p.recoverable(0));  // the listed scenario: a bias and a partial loss
  EXPECT_EQ(p.unrecoverable(), 12);
  EXPECT_EQ(p.left_out(), 12);
  for (std::size_t i = 1; i < p.scenarios(); ++i) EXPECT_FALSE(p.counted(i));
  // The objective is then the listed scenario's alone.
  tune::SerialEvaluator serial;
  const std::vector<tune::CandidateOutcome> o =
      p.evaluate(std::span<const sim::ControllerConfig>(&p.job().controller, 1), serial);
  EXPECT_EQ(o[0].evaluation.objective, o[0].evaluation.scenarios[0].errors.ise);
  j["ensemble"]["unrecoverable"] = "include";
  const tune::TuningProblem all(tune::parse_job(j, "x"));
  EXPECT_EQ(all.unrecoverable(), 12);
  EXPECT_EQ(all.left_out(), 0);
  EXPECT_TRUE(all.counted(5));
}

TEST(TuningProblem, ObjectiveOfXTakesLogScaleParametersInTheirOwnUnits) {
  json j = short_table1_job();
  j["tuning"]["parameters"] = {{"Kp", {1, 50}},
                               {"switching_gain", {{"bounds", {2, 200}}, {"scale", "log"}}}};
  const tune::TuningProblem p(tune::parse_job(j, "x"));
  const std::vector<double> x = {100.0, 20.0};  // switching_gain, Kp: values, not logarithms
  sim::ControllerConfig c = p.job().controller;
  c.switching_gain = 100.0;
  c.Kp = 20.0;
  EXPECT_EQ(p.objective(x), p.simulate(c, 0).metrics.errors.ise);
  EXPECT_THROW(p.objective(std::vector<double>{300.0, 20.0}), InputError);
  EXPECT_THROW(p.objective(std::vector<double>{1.0, 20.0}), InputError);
}

TEST(TuningProblem, NoiseFloorProbeNudgesInitialStatesFromTheReservedStream) {
  const tune::TuningProblem p(short_job());
  const tune::TuningProblem q = p.perturbed(1, tune::kNoiseFloorStream + 3, 1e-12);
  tune::SplitMix64 r = tune::SplitMix64::member(1, 1000003);
  const std::vector<double> x0 = p.scenario(0).initial_state;
  const std::vector<double> x1 = q.scenario(0).initial_state;
  ASSERT_EQ(x1.size(), 6u);
  for (std::size_t i = 0; i < x0.size(); ++i) {
    EXPECT_EQ(x1[i], x0[i] * (1.0 + 1e-12 * (2.0 * r.uniform() - 1.0))) << i;
    EXPECT_NE(x1[i], x0[i]);
  }
}

// Memory by design (issue 29): a problem generates its ensemble's members block by block and
// holds none of them; its scores, the summaries' values and the noise-floor probe are those of
// the same scenarios held, to the last bit, over several blocks.
TEST(TuningProblem, GeneratedMembersScoreAsTheExpandedEnsembleToTheBit) {
  json j = short_ensemble_job();
  j["scenarios"][0]["duration"] = 0.05;
  j["scenarios"][0]["faults"][0]["onset"] = 0.01;
  j["scenarios"][0]["faults"][1]["onset"] = 0.02;
  j["ensemble"]["count"] = 700;
  j["ensemble"]["faults"]["onset"] = {{"uniform", {0.01, 0.04}}};
  j["objective"]["window"] = {0, 0.05};
  const tune::Job job = tune::parse_job(j, "x");
  const tune::TuningProblem streamed(job);
  std::vector<sim::Scenario> all = job.scenarios;
  for (sim::Scenario& m : tune::expand_ensemble(job)) all.push_back(std::move(m));
  const tune::TuningProblem held(job, all, job.scenarios.size());
  ASSERT_EQ(streamed.scenarios(), 701u);
  EXPECT_EQ(streamed.held_scenarios(), 1u);
  EXPECT_EQ(held.held_scenarios(), 701u);
  EXPECT_EQ(streamed.unrecoverable(), held.unrecoverable());
  EXPECT_EQ(streamed.left_out(), held.left_out());
  for (std::size_t i = 0; i < all.size(); ++i) {
    ASSERT_EQ(streamed.recoverable(i), held.recoverable(i)) << i;
    ASSERT_EQ(streamed.counted(i), held.counted(i)) << i;
  }
  for (const std::size_t i : {0, 1, 350, 700})
    EXPECT_EQ(tune::to_json(streamed.scenario(i)), tune::to_json(all[i])) << i;
  // 40 controllers: blocks of 256 scenarios, three of them.
  std::vector<sim::ControllerConfig> controllers;
  for (int k = 0; k < 40; ++k) {
    sim::ControllerConfig c = job.controller;
    c.Kp = 1.0 + 1.25 * k;
    c.switching_gain = k % 2 ? 2.5 : 20.0;
    controllers.push_back(c);
  }
  tune::TbbEvaluator evaluator(2);
  const std::vector<tune::CandidateOutcome> a = streamed.evaluate(controllers, evaluator);
  const std::vector<tune::CandidateOutcome> b = held.evaluate(controllers, evaluator);
  for (std::size_t i = 0; i < controllers.size(); ++i) {
    const tune::Evaluation &x = a[i].evaluation, &y = b[i].evaluation;
    EXPECT_EQ(x.objective, y.objective) << i;
    EXPECT_EQ(x.fitness, y.fitness) << i;
    EXPECT_EQ(x.diverged_count, y.diverged_count) << i;
    EXPECT_EQ(x.values, y.values) << i;
    EXPECT_EQ(x.scenarios.size(), 1u);  // the listed one's metrics only
    EXPECT_EQ(y.scenarios.size(), 701u);
    const tune::Summary p = streamed.summarize(x), q = held.summarize(y);
    EXPECT_EQ(p.scenarios, 701);
    EXPECT_EQ(p.p90, q.p90) << i;
    EXPECT_EQ(p.cvar, q.cvar) << i;
    EXPECT_EQ(p.diverged, q.diverged) << i;
  }
  // The noise-floor probe nudges a generated member as it nudges the member held.
  const std::uint64_t k = tune::kNoiseFloorStream + 2;
  const tune::TuningProblem ps = streamed.perturbed(1, k, 1e-6), ph = held.perturbed(1, k, 1e-6);
  EXPECT_EQ(tune::to_json(ps.scenario(500)), tune::to_json(ph.scenario(500)));
  EXPECT_NE(tune::to_json(ps.scenario(500)), tune::to_json(all[500]));
  const tune::Evaluation pe = ps.evaluate(std::span(controllers).first(1), evaluator)[0].evaluation;
  const tune::Evaluation he = ph.evaluate(std::span(controllers).first(1), evaluator)[0].evaluation;
  EXPECT_EQ(pe.values, he.values);
  EXPECT_EQ(pe.objective, he.objective);
  EXPECT_NE(pe.values, a[0].evaluation.values);
}

// Memory by design (issue 29): scoring a controller on 10^5 ensemble members takes hardly more
// memory than on 10^3: a few numbers per member and one block of scenarios. An expanded ensemble
// took about 2 kB a member (200 MB more at 10^5). Measured in a child process, by its peak
// resident set over its size when it began.
TEST(TuningProblem, PeakMemoryDoesNotGrowWithTheMemberCount) {
  if (const char* why = ftc::testing::why_no_peak()) GTEST_SKIP() << why;
  const auto growth_kb = [](std::int64_t members) {
    return ftc::testing::peak_growth_kb([members] {
      json j = tiny_job("members");
      j["scenarios"][0]["duration"] = 0.02;
      j["scenarios"][0]["faults"] = json::array();
      j["objective"]["window"] = {0, 0.02};
      j["ensemble"] = {{"count", members}, {"seed", 1}};
      const tune::TuningProblem p(tune::parse_job(j, "m"));
      tune::SerialEvaluator serial;
      const sim::ControllerConfig c = p.job().controller;
      const tune::CandidateOutcome o =
          p.evaluate(std::span<const sim::ControllerConfig>(&c, 1), serial)[0];
      return o.evaluation.values.size() == static_cast<std::size_t>(members) + 1 &&
             p.held_scenarios() == 1 && std::isfinite(o.evaluation.objective);
    });
  };
  const long small = growth_kb(1000), large = growth_kb(100000);
  ASSERT_GE(small, 0);
  ASSERT_GE(large, 0);
  // 10^5 members of 8 bytes and a block of 8192 scenarios are about 15 MB; 40 MB is a generous
  // bound that an expanded ensemble (about 200 MB) would break.
  EXPECT_LT(large - small, 40 * 1024)
      << "peak grew by " << small << " kB at 10^3 members and by " << large << " kB at 10^5";
}

// Capping (issue 27): counting the unknown values as 0 bounds every aggregate from below, to the
// last bit, however many values are known; with all known it is the aggregate itself, and
// knowing more never lowers it.
TEST(Capping, BoundIsALowerBoundOfEveryAggregate) {
  std::mt19937_64 rng(27);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<tune::ObjectiveConfig> aggregates;
  for (const tune::Aggregate a : {tune::Aggregate::mean, tune::Aggregate::max}) {
    tune::ObjectiveConfig o;
    o.aggregate = a;
    aggregates.push_back(o);
  }
  for (const double q : {0.0, 0.5, 0.9, 0.99, 1.0}) {
    tune::ObjectiveConfig o;
    o.aggregate = tune::Aggregate::quantile;
    o.q = q;
    aggregates.push_back(o);
    o.aggregate = tune::Aggregate::cvar;
    o.alpha = q == 1.0 ? 0.999 : q;
    aggregates.push_back(o);
  }
  int strictly_below = 0;
  for (const tune::ObjectiveConfig& o : aggregates) {
    for (int trial = 0; trial < 300; ++trial) {
      const std::size_t n = 1 + static_cast<std::size_t>(u(rng) * 60);
      std::vector<double> v(n);
      for (double& x : v) {
        const double r = u(rng);
        // Values over 12 decades, some exactly 0, some diverged (+inf), many alike.
        x = r < 0.05   ? 0.0
            : r < 0.08 ? std::numeric_limits<double>::infinity()
            : r < 0.2  ? 0.1
                       : std::pow(10.0, -6.0 + 12.0 * u(rng));
      }
      const double full = o.aggregate_of(v);
      std::vector<bool> known(n, false);
      double previous = 0.0;
      // Reveal the values one by one in a random order.
      std::vector<std::size_t> reveal(n);
      for (std::size_t i = 0; i < n; ++i) reveal[i] = i;
      std::shuffle(reveal.begin(), reveal.end(), rng);
      for (std::size_t k = 0; k <= n; ++k) {
        if (k > 0) known[reveal[k - 1]] = true;
        const double bound = tune::aggregate_lower_bound(o, v, known);
        ASSERT_LE(bound, full) << tune::to_string(o.aggregate) << " n=" << n << " k=" << k;
        ASSERT_GE(bound, previous) << tune::to_string(o.aggregate);
        strictly_below += bound < full ? 1 : 0;
        previous = bound;
      }
      EXPECT_EQ(previous, full);  // all known: the aggregate, bit for bit
    }
  }
  EXPECT_GT(strictly_below, 1000);
}

TEST(Capping, HardestFirstPutsTheCountedScenariosInDescendingOrder) {
  const double inf = std::numeric_limits<double>::infinity();
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const std::vector<double> ref = {1.0, 5.0, inf, 5.0, 0.5, nan, 9.0};
  const std::vector<bool> counted = {true, true, true, true, true, true, false};
  // +inf and NaN (as +inf) first in index order, then 5 (1 before 3), 1, 0.5; the uncounted last.
  EXPECT_EQ(tune::hardest_first(ref, counted), (std::vector<std::size_t>{2, 5, 1, 3, 0, 4, 6}));
  EXPECT_EQ(tune::hardest_first({}, counted), (std::vector<std::size_t>{0, 1, 2, 3, 4, 5, 6}));
  EXPECT_EQ(tune::capping_block(7, 3), 2u);
  EXPECT_EQ(tune::capping_block(101, 8), 8u);
  EXPECT_EQ(tune::capping_block(101, 1), 26u);
  EXPECT_EQ(tune::capping_block(1001, 100), 4u);
  EXPECT_EQ(tune::capping_block(1, 1), 1u);
}

// A candidate that runs to the end under capping has evaluate()'s outcome to the last bit; a
// capped one stopped with a bound below its true objective and a fitness bound below its cap.
TEST(Capping, CappedCandidatesStopBelowTheirCapAndTheOthersScoreExactly) {
  json j = short_ensemble_job();
  j["ensemble"]["count"] = 11;
  const tune::TuningProblem problem(tune::parse_job(j, "x"));
  std::vector<sim::ControllerConfig> controllers;
  for (const double kp : {20.0, 1.0, 50.0, 8.0, 35.0, 3.0})
    for (const double eta : {20.0, 2.5}) {
      sim::ControllerConfig c = problem.job().controller;
      c.Kp = kp;
      c.switching_gain = eta;
      controllers.push_back(c);
    }
  tune::TbbEvaluator evaluator(2);
  const std::vector<tune::CandidateOutcome> exact = problem.evaluate(controllers, evaluator);
  // Caps: the fitness of the median candidate for three in four, none for the others.
  std::vector<double> fitness;
  for (const tune::CandidateOutcome& o : exact) fitness.push_back(o.evaluation.fitness);
  std::vector<double> sorted = fitness;
  std::sort(sorted.begin(), sorted.end());
  const double median = sorted[sorted.size() / 2];
  std::vector<double> caps(controllers.size(), tune::kNoCap);
  for (std::size_t i = 0; i < caps.size(); ++i)
    if (i % 4 != 1) caps[i] = median;
  std::vector<bool> counted;
  std::vector<double> reference;
  for (std::size_t s = 0; s < problem.scenarios(); ++s) {
    counted.push_back(problem.counted(s));
    reference.push_back(exact[0].evaluation.values[s]);
  }
  for (const bool hardest : {true, false}) {
    const std::vector<std::size_t> order =
        tune::hardest_first(hardest ? reference : std::vector<double>{}, counted);
    const std::vector<tune::CandidateOutcome> capped =
        problem.evaluate_capped(controllers, caps, order, evaluator);
    int stopped = 0;
    for (std::size_t i = 0; i < controllers.size(); ++i) {
      const tune::Evaluation& c = capped[i].evaluation;
      const tune::Evaluation& e = exact[i].evaluation;
      if (!c.capped) {
        EXPECT_EQ(c.simulated, problem.scenarios());
        EXPECT_EQ(c.objective, e.objective) << i;
        EXPECT_EQ(c.fitness, e.fitness) << i;
        EXPECT_EQ(c.diverged_count, e.diverged_count) << i;
        continue;
      }
      ++stopped;
      EXPECT_NE(caps[i], tune::kNoCap) << "a candidate without a cap was capped";
      EXPECT_LT(c.simulated, problem.scenarios());
      EXPECT_LE(c.objective, e.objective) << i;
      EXPECT_LT(c.fitness, caps[i]) << i;
      EXPECT_LT(e.fitness, caps[i]) << "capped although it mattered: " << i;
      EXPECT_LE(c.diverged_count, e.diverged_count);
    }
    EXPECT_GT(stopped, 0) << "nothing was capped: the test would prove nothing";
  }
}

namespace {

bool same_or_both_nan(double a, double b) { return a == b || (std::isnan(a) && std::isnan(b)); }

}  // namespace

// Capping with goals (issue 27): the metrics whose aggregate has a lower bound while members
// are unknown are those defined on every member, as the metrics record marks them.
TEST(Capping, GoalsOfMetricsDefinedOnEveryMemberHaveALowerBound) {
  const char* bounded[] = {"ise", "iae", "itae", "control_tv", "control_energy", "peak_command"};
  const char* unbounded[] = {"saturation_fraction", "peak_error_after_fault", "settling_time",
                             "steady_state_error"};
  tune::GoalConfig g;
  for (const char* m : bounded) {
    g.metric = &sim::metric_field(m);
    EXPECT_TRUE(tune::goal_has_lower_bound(g)) << m;
  }
  for (const char* m : unbounded) {
    g.metric = &sim::metric_field(m);
    EXPECT_FALSE(tune::goal_has_lower_bound(g)) << m;
  }
  // Every metric a goal may name is one of the two.
  std::size_t goals = 0;
  for (const sim::MetricField& f : sim::kMetricFields) goals += f.goal ? 1 : 0;
  EXPECT_EQ(goals, std::size(bounded) + std::size(unbounded));
}

// The bound on a candidate's constrained fitness from lower bounds of its objective and its
// violation is above the fitness of every candidate with values at least those (so a capped
// candidate could not have been accepted), even for violations one ulp apart, and equal to or
// above the fitness of the bounds themselves (a tie with the cap is never capped).
TEST(Capping, FitnessUpperBoundFollowsTheConstraintRule) {
  const double inf = std::numeric_limits<double>::infinity();
  EXPECT_EQ(tune::fitness_upper_bound(4.0, 0.0), 0.25);  // no violation: fitness_of(objective)
  EXPECT_EQ(tune::fitness_upper_bound(inf, 0.0), 0.0);
  EXPECT_EQ(tune::fitness_upper_bound(0.0, 0.0), inf);
  EXPECT_EQ(tune::fitness_upper_bound(4.0, inf), -1.0);  // infinite violation: exactly -1
  // Where the rounded ratio V/(1 + V) falls as V grows (1 at 2^53, 1 - 2^-52 one ulp above).
  const double v53 = 0x1p53, above = std::nextafter(v53, inf);
  ASSERT_LT(tune::constrained_fitness(0.0, v53), tune::constrained_fitness(0.0, above));
  EXPECT_GE(tune::fitness_upper_bound(1.0, v53), tune::constrained_fitness(0.0, above));
  std::mt19937_64 rng(2627);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  int checked = 0;
  for (int trial = 0; trial < 20000; ++trial) {
    const double v = std::pow(10.0, -320.0 + 620.0 * u(rng));
    const double o = std::pow(10.0, -12.0 + 24.0 * u(rng));
    const double ub = tune::fitness_upper_bound(o, v);
    ASSERT_LT(ub, 0.0) << v;  // a violation bound above 0: the candidate is infeasible
    ASSERT_GE(ub, tune::constrained_fitness(tune::fitness_of(o), v)) << v;  // the tie
    // Larger true violations: the next doubles, and factors up to 2.
    double w = v;
    for (int k = 0; k < 8; ++k) {
      w = std::nextafter(w, inf);
      // (at least: for V above about 2^53 every J rounds to -1, which the bound is then)
      ASSERT_GE(ub, tune::constrained_fitness(tune::fitness_of(o * 2), w)) << v << " " << w;
      ++checked;
    }
    const double far = v * (1.0 + u(rng));
    ASSERT_GE(ub, tune::constrained_fitness(0.0, far)) << v << " " << far;
    ASSERT_GE(ub, -1.0);
    // Any feasible candidate is above it: a feasible cap always caps an infeasible candidate.
    ASSERT_LT(ub, tune::constrained_fitness(tune::fitness_of(o), 0.0));
  }
  EXPECT_EQ(checked, 160000);
}

// A job with goals under capping: a candidate that runs to the end has evaluate()'s outcome
// (goals and violation included) to the last bit; a capped one stopped with every bound on the
// right side (objective, goals of bounded metrics and violation at most the true ones, goals
// without a bound NaN, fitness at least the true one) and could not have been accepted: its
// true fitness is below its cap. A cap equal to the candidate's own fitness (a tie, which the
// Bat algorithm accepts) never caps it.
TEST(Capping, GoalJobsAreCappedOnlyWhereNoDecisionChanges) {
  std::vector<sim::ControllerConfig> controllers;
  tune::TbbEvaluator evaluator(2);
  const auto controllers_for = [&](const tune::TuningProblem& problem) {
    controllers.clear();
    for (const double kp : {20.0, 1.0, 50.0, 8.0, 35.0, 3.0})
      for (const double eta : {20.0, 2.5, 150.0}) {
        sim::ControllerConfig c = problem.job().controller;
        c.Kp = kp;
        c.switching_gain = eta;
        controllers.push_back(c);
      }
  };
  // The limits: the median TV and peak command of these controllers, so that some meet them.
  const tune::TuningProblem loose(tune::parse_job(goal_ensemble_job(1e300, 1e300, true), "x"));
  controllers_for(loose);
  std::vector<double> tv, peak;
  for (const tune::CandidateOutcome& o : loose.evaluate(controllers, evaluator)) {
    tv.push_back(o.evaluation.goals.at(1));
    peak.push_back(o.evaluation.goals.at(2));
  }
  std::sort(tv.begin(), tv.end());
  std::sort(peak.begin(), peak.end());
  const tune::TuningProblem problem(
      tune::parse_job(goal_ensemble_job(tv[tv.size() / 2], peak[peak.size() / 3], true), "x"));
  const std::vector<tune::CandidateOutcome> exact = problem.evaluate(controllers, evaluator);
  std::vector<double> feasible, infeasible;
  for (const tune::CandidateOutcome& o : exact)
    (o.evaluation.feasible() ? feasible : infeasible).push_back(o.evaluation.fitness);
  ASSERT_GE(feasible.size(), 2u);
  ASSERT_GE(infeasible.size(), 2u);
  std::sort(feasible.begin(), feasible.end());
  std::sort(infeasible.begin(), infeasible.end());
  // Caps: none, the candidate's own fitness (a tie), the median feasible fitness, the best
  // infeasible one (the least violation).
  std::vector<double> caps(controllers.size());
  for (std::size_t i = 0; i < caps.size(); ++i)
    caps[i] = i % 4 == 0   ? tune::kNoCap
              : i % 4 == 1 ? exact[i].evaluation.fitness
              : i % 4 == 2 ? feasible[feasible.size() / 2]
                           : infeasible.back();
  std::vector<bool> counted;
  for (std::size_t s = 0; s < problem.scenarios(); ++s) counted.push_back(problem.counted(s));
  const std::vector<std::size_t> order = tune::hardest_first({}, counted);
  const std::vector<tune::CandidateOutcome> capped =
      problem.evaluate_capped(controllers, caps, order, evaluator);
  int stopped = 0, stopped_infeasible = 0, stopped_below_infeasible_cap = 0;
  for (std::size_t i = 0; i < controllers.size(); ++i) {
    const tune::Evaluation& c = capped[i].evaluation;
    const tune::Evaluation& e = exact[i].evaluation;
    ASSERT_EQ(c.goals.size(), 4u);
    if (!c.capped) {
      EXPECT_EQ(c.simulated, problem.scenarios());
      EXPECT_EQ(c.objective, e.objective) << i;
      EXPECT_EQ(c.fitness, e.fitness) << i;
      EXPECT_EQ(c.violation, e.violation) << i;
      for (std::size_t k = 0; k < 4; ++k)
        EXPECT_TRUE(same_or_both_nan(c.goals[k], e.goals[k])) << i;
      continue;
    }
    ++stopped;
    EXPECT_NE(i % 4, 0u) << "a candidate without a cap was capped";
    EXPECT_NE(i % 4, 1u) << "a tie with the cap was capped: the Bat algorithm accepts it";
    EXPECT_LT(c.simulated, problem.scenarios());
    EXPECT_LE(c.objective, e.objective) << i;
    EXPECT_LT(c.fitness, caps[i]) << i;
    EXPECT_GE(c.fitness, e.fitness) << i;
    EXPECT_LT(e.fitness, caps[i]) << "capped although it mattered: " << i;
    for (std::size_t k = 0; k < 3; ++k) EXPECT_LE(c.goals[k], e.goals[k]) << i << " " << k;
    EXPECT_TRUE(std::isnan(c.goals[3])) << "steady_state_error has no lower bound";
    EXPECT_LE(c.violation, e.violation) << i;
    stopped_infeasible += c.violation > 0 ? 1 : 0;
    stopped_below_infeasible_cap += caps[i] < 0 ? 1 : 0;
  }
  // The test proves something only when candidates stopped on their limits, against feasible
  // and infeasible caps.
  EXPECT_GT(stopped, 0);
  EXPECT_GT(stopped_infeasible, 0);
  EXPECT_GT(stopped_below_infeasible_cap, 0);
}

TEST(TuningProblem, AFrontsFitnessGivesEachCandidatesSoftGoalsAndViolation) {
  // A job with two soft goals and a hard one: the multi-objective side of the seam gives, per
  // candidate, the soft goals' values in the job's order and the hard goal's violation, the
  // same numbers its trial records; a job of one soft goal has no objective vectors.
  json j = tiny_job("front");
  j.erase("objective");
  j["goals"] = {{{"metric", "control_tv"}, {"minimize", true}},
                {{"metric", "peak_command"}, {"at_most", 1e-3}},
                {{"metric", "ise"}, {"minimize", true}}};
  j["tuning"]["algorithm"] = {{"type", "random"}, {"population", 2}, {"iterations", 0}};
  const tune::TuningProblem p(tune::parse_job(j, "front"));
  tune::SerialEvaluator serial;
  tune::ProblemFitness fitness(p, serial);
  ASSERT_EQ(fitness.objectives(), 2u);
  const std::vector<tune::Decision> batch = {{20.0, 5.0}, {10.0, 2.0}};  // Kp, Ki
  ASSERT_EQ(batch[0].size(), p.space().dimension());
  const std::vector<tune::ObjectiveVector> F = fitness.objective_vectors(batch);
  ASSERT_EQ(F.size(), 2u);
  ASSERT_EQ(fitness.trials().size(), 2u);
  for (std::size_t i = 0; i < F.size(); ++i) {
    const tune::Trial& t = fitness.trials()[i];
    ASSERT_EQ(F[i].values.size(), 2u);
    EXPECT_EQ(F[i].values[0], t.goals[0]);  // control_tv
    EXPECT_EQ(F[i].values[1], t.goals[2]);  // ise
    EXPECT_GT(F[i].values[0], 0.0);
    EXPECT_EQ(F[i].violation, t.violation);
    EXPECT_GT(F[i].violation, 0.0);  // a 1e-3 limit on the peak command is not met
    EXPECT_FALSE(F[i].feasible());
  }
  EXPECT_EQ(fitness.simulations(), 2);
  // The run's optimiser of a front: random search samples one.
  EXPECT_NE(tune::make_optimizer(p, *p.job().tuning->algorithm, 1), nullptr);

  // One soft goal: a problem of one objective.
  json one = tiny_job("one");
  one.erase("objective");
  one["goals"] = {{{"metric", "ise"}, {"minimize", true}}};
  const tune::TuningProblem q(tune::parse_job(one, "one"));
  tune::ProblemFitness single(q, serial);
  EXPECT_EQ(single.objectives(), 0u);
  EXPECT_THROW(single.objective_vectors(batch), std::logic_error);
}
