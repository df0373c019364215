#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>

#include "cli_runner.hpp"
#include "ftc/runtime/gains.hpp"
#include "ftc/sim/simulation.hpp"
#include "ftc/sim/spacecraft.hpp"
#include "ftc/tune/evaluators/tbb_evaluator.hpp"
#include "ftc/tune/problem/problem.hpp"
#include "ftc/tune/run/documents.hpp"
#include "ftc/tune/run/tuning_run.hpp"
#include "short_job.hpp"

using nlohmann::json;
using namespace ftc;
using namespace ftc::testing;

namespace {
tune::Job short_job() { return tune::parse_job(short_table1_job(), "short"); }
}  // namespace

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
