#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>

#include "cli_runner.hpp"
#include "ftc/runtime/gains.hpp"
#include "ftc/sim/simulation.hpp"
#include "ftc/sim/spacecraft.hpp"
#include "ftc/tune/evaluators/tbb_evaluator.hpp"
#include "ftc/tune/job/ensemble.hpp"
#include "ftc/tune/problem/problem.hpp"
#include "ftc/tune/run/documents.hpp"
#include "ftc/tune/run/tuning_run.hpp"
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
  const std::vector<double>& x0 = p.scenario(0).initial_state;
  const std::vector<double>& x1 = q.scenario(0).initial_state;
  ASSERT_EQ(x1.size(), 6u);
  for (std::size_t i = 0; i < x0.size(); ++i) {
    EXPECT_EQ(x1[i], x0[i] * (1.0 + 1e-12 * (2.0 * r.uniform() - 1.0))) << i;
    EXPECT_NE(x1[i], x0[i]);
  }
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
