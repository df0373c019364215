#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <bit>
#include <cmath>
#include <fstream>
#include <limits>
#include <map>
#include <nlohmann/json.hpp>
#include <regex>
#include <sstream>

#include "cli_runner.hpp"
#include "ftc/runtime/gains.hpp"
#include "ftc/sim/simulation.hpp"
#include "ftc/sim/spacecraft.hpp"
#include "ftc/tune/evaluators/tbb_evaluator.hpp"
#include "ftc/tune/io/files.hpp"
#include "ftc/tune/problem/problem.hpp"
#include "ftc/tune/run/documents.hpp"
#include "ftc/tune/run/tuning_run.hpp"
#include "goal_job.hpp"
#include "short_job.hpp"

using nlohmann::json;
using namespace ftc;
using namespace ftc::testing;

namespace {

// The run of `job` on 2 threads resumed from `state` writes the gains file and trials.csv of the
// uninterrupted run `whole`.
void expect_resumed_run_writes_the_same(const tune::Job& job, const json& state,
                                        const tune::TuningOutcome& whole) {
  tune::RunOptions resume;
  resume.resume = &state;
  const tune::TuningOutcome resumed = tuned(job, 2, std::nullopt, resume);
  EXPECT_EQ(tune::gains_document(resumed).dump(), tune::gains_document(whole).dump());
  EXPECT_EQ(tune::trials_csv(resumed), tune::trials_csv(whole));
}

}  // namespace

TEST(TuningRun, FinishesWhenSomeCandidatesDiverge) {
  json j = short_table1_job();
  // c2 above about 9e4 diverges at 1 ms sampling (ftctune simulate --set c2=...: 6e4 gives
  // ISE 1e8, 9e4 diverges), so this box holds both kinds.
  j["tuning"]["parameters"] = {{"c2", {1e3, 3e5}}};
  const tune::TuningProblem problem(tune::parse_job(j, "x"));
  tune::TbbEvaluator parallel(2);
  tune::ProblemFitness fitness(problem, parallel);
  // Counts the candidates that scored 0 on their way to the optimiser.
  struct Counting final : tune::BatchFitness {
    tune::BatchFitness& inner;
    int zeros = 0, total = 0;
    explicit Counting(tune::BatchFitness& f) : inner(f) {}
    std::vector<double> operator()(const std::vector<tune::Decision>& batch) override {
      std::vector<double> J = inner(batch);
      for (double v : J) zeros += v == 0.0, ++total;
      return J;
    }
  } counting(fitness);
  auto optimizer = problem.job().tuning->algorithm->make(1, problem.space());
  const tune::OptimizationResult r = tune::run_optimizer(*optimizer, counting);
  EXPECT_TRUE(r.completed);
  EXPECT_EQ(counting.total, 9);
  EXPECT_GT(counting.zeros, 0) << "no candidate diverged: the test would prove nothing";
  EXPECT_LT(counting.zeros, 9);
  EXPECT_GT(r.best_fitness, 0.0);
}

TEST(TuningRun, GainsIdenticalForOneAndTwoThreads) {
  const tune::Job job = short_job();
  const std::string one = tune::gains_document(tuned(job, 1)).dump();
  const std::string two = tune::gains_document(tuned(job, 2)).dump();
  EXPECT_EQ(one, two);
}

TEST(TuningRun, OtherSeedOtherHistory) {
  const tune::Job job = short_job();
  const tune::TuningOutcome a = tuned(job, 2);
  const tune::TuningOutcome b = tuned(job, 2, 2);
  EXPECT_EQ(b.seed, 2u);
  EXPECT_NE(a.optimization.history.front().best, b.optimization.history.front().best);
}

TEST(TuningRun, TunedFitnessIsReproducedByComparison) {
  const tune::TuningOutcome r = tuned(short_job(), 2);
  EXPECT_EQ(r.best().role, "tuned");
  EXPECT_EQ(r.best().outcome.evaluation.fitness, r.optimization.best_fitness);
  EXPECT_EQ(r.baseline().controller.Kp, 20.0);
  EXPECT_EQ(r.comparison.size(), 4u);
  EXPECT_EQ(r.comparison[0].label, "NFTSMC");
  // 9 candidates but those the cache served, 4 compared controllers, the winner 8 times more for
  // the noise floor, and once more per parameter on a bound (1 % of the range inward).
  int at_bound = 0;
  for (std::size_t j = 0; j < r.job.tuning->parameters.size(); ++j)
    at_bound += tune::inward_value(r.job.tuning->parameters[j], r.optimization.best[j]) ? 1 : 0;
  const auto served = tune::cached_trials(r.trials);
  EXPECT_EQ(r.simulations, 9 - served + 4 + 8 + at_bound);
  ASSERT_TRUE(r.noise_floor.has_value());
  EXPECT_LE(r.noise_floor->objective_min, r.noise_floor->objective_max);
  EXPECT_GT(r.noise_floor->relative_spread, 0.0);  // chaotic at rounding level after the faults
}

TEST(Cli, RunWritesGainsIdenticalAcrossThreadCounts) {
  const auto dir = fresh_dir("run");
  {
    std::ofstream f(dir / "job.json");
    f << short_table1_job().dump(2);
  }
  const std::string job = std::string("'").append((dir / "job.json").string()).append("'");
  const CliResult a =
      run_cli("run " + job + " --threads 1 --out '" + (dir / "t1").string() + "'", dir);
  ASSERT_EQ(a.exit_code, 0) << a.err;
  EXPECT_NE(a.err.find("iteration 2/2: best J ="), std::string::npos) << a.err;
  const CliResult b =
      run_cli("run " + job + " --threads 2 -q --out '" + (dir / "t2").string() + "'", dir);
  ASSERT_EQ(b.exit_code, 0) << b.err;
  EXPECT_EQ(b.err, "");  // --quiet
  for (const char* f :
       {"gains.json", "history.csv", "comparison.json", "comparison.md", "run.json"})
    EXPECT_TRUE(std::filesystem::exists(dir / "t1" / f)) << f;
  EXPECT_EQ(slurp(dir / "t1" / "gains.json"), slurp(dir / "t2" / "gains.json"));
  EXPECT_EQ(json::parse(slurp(dir / "t2" / "run.json"))["threads"], 2);
  EXPECT_EQ(json::parse(slurp(dir / "t1" / "run.json"))["threads"], 1);

  std::istringstream hist(slurp(dir / "t1" / "history.csv"));
  std::string header;
  std::getline(hist, header);
  EXPECT_EQ(header, "iteration,best_fitness,Kp,Ki,mean_loudness,mean_pulse_rate,evaluations");
  const std::string md = slurp(dir / "t1" / "comparison.md");
  for (const char* label : {"| NFTSMC", "| FOSMC", "| PI-FOSMC (job)", "| tuned PI-FOSMC"})
    EXPECT_NE(md.find(label), std::string::npos) << label;

  // The loaded gains drive `simulate` to the tuned objective.
  const CliResult s =
      run_cli("simulate " + job + " --gains '" + (dir / "t1" / "gains.json").string() +
                  "' -q --out '" + (dir / "sim").string() + "'",
              dir);
  ASSERT_EQ(s.exit_code, 0) << s.err;
  const json g = json::parse(slurp(dir / "t1" / "gains.json"));
  const json m = json::parse(slurp(dir / "sim" / "metrics.json"));
  EXPECT_EQ(m["objective"], g["objective"]["value"]);
  EXPECT_EQ(m["controller"]["Kp"], g["controller"]["Kp"]);
}

TEST(Cli, ValidateSummarisesOrListsEveryError) {
  const auto dir = fresh_dir("validate");
  CliResult r = run_cli("validate jobs/table1.json", dir);
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("110 evaluations x 1 scenario, 30000 simulated steps per evaluation"),
            std::string::npos)
      << r.out;
  json bad = short_table1_job();
  bad["controller"]["Kp"] = 0;
  bad["tuning"]["parameters"]["Kp"] = {60, 50};
  bad["scenarios"][0]["faults"][0]["actuator"] = 7;
  {
    std::ofstream f(dir / "bad.json");
    f << bad.dump();
  }
  r = run_cli("validate '" + (dir / "bad.json").string() + "'", dir);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("3 problems"), std::string::npos) << r.err;
  for (const char* p :
       {"/controller/Kp", "/tuning/parameters/Kp", "/scenarios/0/faults/0/actuator"})
    EXPECT_NE(r.err.find(p), std::string::npos) << p;
}

TEST(Cli, RunWithoutTuningSectionExitsTwo) {
  const auto dir = fresh_dir("notuning");
  json j = short_table1_job();
  j.erase("tuning");
  {
    std::ofstream f(dir / "job.json");
    f << j.dump();
  }
  const CliResult r = run_cli("run '" + (dir / "job.json").string() + "'", dir);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("/tuning: is required by ftctune run"), std::string::npos) << r.err;
}

// An evaluator that asks its interrupt before each batch and counts the batches.
struct CountingEvaluator final : tune::BatchEvaluator {
  std::vector<tune::TaskResult> run(const tune::SimulationBatch& batch) override {
    if (interrupted()) throw tune::Interrupted();
    ++batches;
    return inner.run(batch);
  }
  int concurrency() const override { return 1; }
  std::string name() const override { return "counting"; }
  tune::SerialEvaluator inner;
  int batches = 0;
};

// An interrupt (a cancel in the service) asked between packs ends the run within its iteration,
// at the iteration before: the same history, trials and best as a run the observer stopped
// after that iteration, with the TBB and the serial evaluator alike. Cut short in the first
// iteration, the run has nothing to keep.
TEST(TuningRun, AnInterruptEndsTheRunAtItsLastFinishedIteration) {
  const tune::Job job = short_job();
  tune::RunOptions stop;
  stop.observer = [&](const tune::HistoryRow& h, const tune::Optimizer&,
                      const std::vector<tune::Trial>&) { return h.iteration < 1; };
  const tune::TuningOutcome stopped = tuned(job, 1, std::nullopt, stop);
  ASSERT_EQ(stopped.optimization.history.size(), 2u);
  tune::TbbEvaluator tbb(2);
  tune::SerialEvaluator serial;
  for (tune::BatchEvaluator* e : std::initializer_list<tune::BatchEvaluator*>{&tbb, &serial}) {
    std::atomic<int> finished{0}, asked{0};  // asked from worker threads
    tune::RunOptions o;
    o.observer = [&](const tune::HistoryRow&, const tune::Optimizer&,
                     const std::vector<tune::Trial>&) { return ++finished > 0; };
    o.interrupt = [&] {
      ++asked;
      return finished.load() >= 2;  // during iteration 2, at its first pack
    };
    const tune::TuningOutcome r = tune::tune(job, *e, o);
    EXPECT_TRUE(r.interrupted) << e->name();
    EXPECT_FALSE(r.completed());
    EXPECT_TRUE(r.comparison.empty());  // nothing compared: the caller decides
    EXPECT_GT(asked.load(), 0);
    EXPECT_EQ(tune::trials_csv(r), tune::trials_csv(stopped)) << e->name();
    EXPECT_EQ(tune::history_csv(r), tune::history_csv(stopped)) << e->name();
    EXPECT_EQ(r.optimization.best, stopped.optimization.best);
    EXPECT_FALSE(e->interrupted());  // the interrupt is the run's only
  }
  tune::RunOptions first;
  first.interrupt = [] { return true; };
  const tune::TuningOutcome none = tune::tune(job, tbb, first);
  EXPECT_TRUE(none.interrupted);
  EXPECT_TRUE(none.optimization.history.empty());
  EXPECT_TRUE(none.trials.empty());

  // An optimiser that scores an iteration in several batches (pagmo's sade, one candidate at a
  // time) records the trials of the batches before the cut: they are dropped with the iteration.
  json one_by_one = short_table1_job();
  one_by_one["tuning"]["algorithm"] = {
      {"type", "pagmo"}, {"name", "sade"}, {"population", 7}, {"generations", 2}};
  const tune::Job sade = tune::parse_job(one_by_one, "sade");
  const tune::TuningOutcome sade_stopped = tuned(sade, 1, std::nullopt, stop);
  CountingEvaluator counting;
  int finished = 0, at_cut = 0;
  tune::RunOptions o;
  o.observer = [&](const tune::HistoryRow&, const tune::Optimizer&,
                   const std::vector<tune::Trial>&) {
    if (++finished == 2) at_cut = counting.batches;
    return true;
  };
  o.interrupt = [&] { return finished >= 2 && counting.batches >= at_cut + 3; };
  const tune::TuningOutcome cut = tune::tune(sade, counting, o);
  ASSERT_TRUE(cut.interrupted);
  EXPECT_EQ(counting.batches, at_cut + 3);  // three batches of iteration 2 ran
  EXPECT_EQ(tune::trials_csv(cut), tune::trials_csv(sade_stopped));
  EXPECT_EQ(tune::history_csv(cut), tune::history_csv(sade_stopped));

  // Resumed from a checkpoint and cut in its first iteration: the checkpoint's run, as it was.
  const json state = checkpoint_after(job, 0);
  tune::RunOptions resumed;
  resumed.resume = &state;
  resumed.interrupt = [] { return true; };
  const tune::TuningOutcome back = tune::tune(job, serial, resumed);
  EXPECT_TRUE(back.interrupted);
  ASSERT_EQ(back.optimization.history.size(), 1u);
  EXPECT_EQ(back.trials.size(), state["trials"].size());
  tune::RunOptions stop0;
  stop0.observer = [&](const tune::HistoryRow&, const tune::Optimizer&,
                       const std::vector<tune::Trial>&) { return false; };
  EXPECT_EQ(tune::trials_csv(back), tune::trials_csv(tuned(job, 1, std::nullopt, stop0)));
}

// "noise_floor": "picked" (issue 42): a front's noise floor is measured at the picked point only,
// the same values there as when every point is probed, the other points' floors unknown, and
// 8 × (points - 1) × scenarios simulations fewer; nothing else changes.
TEST(TuningRun, AFrontsNoiseFloorAtThePickedPointOnlyCostsOnePointsReruns) {
  json j = front_job();
  const tune::TuningOutcome every = tuned(tune::parse_job(j, "front"), 1);
  j["tuning"]["noise_floor"] = "picked";
  const tune::TuningOutcome picked = tuned(tune::parse_job(j, "front"), 1);
  ASSERT_TRUE(every.front && picked.front);
  const std::size_t n = every.front->points.size(), k = every.front->picked;
  ASSERT_GE(n, 2u) << "a front of one point would prove nothing";
  ASSERT_EQ(picked.front->points.size(), n);
  EXPECT_EQ(picked.front->picked, k);
  for (std::size_t i = 0; i < n; ++i) {
    const auto& floor = picked.front->points[i].noise_floor;
    if (i == k) {
      EXPECT_EQ(floor, every.front->points[i].noise_floor);
      EXPECT_TRUE(floor[0].has_value());
    } else {
      for (const auto& f : floor) EXPECT_FALSE(f.has_value()) << i;
    }
  }
  EXPECT_EQ(tune::gains_document(picked)["noise_floor"],
            tune::gains_document(every)["noise_floor"]);
  EXPECT_EQ(tune::gains_document(picked)["tuned"], tune::gains_document(every)["tuned"]);
  EXPECT_EQ(every.simulations - picked.simulations,
            static_cast<std::int64_t>(8 * (n - 1) * every.scenarios));
}

// A goal a trial could not measure is an empty cell of trials.csv (it was "–", which made a CSV
// reader take the whole column for text); pick reads it back as the NaN it was.
TEST(TuningRun, TrialsCsvLeavesAnUndefinedValueEmpty) {
  tune::TuningOutcome r = tuned(tune::parse_job(front_job(), "front"), 1);
  ASSERT_FALSE(r.trials.empty());
  ASSERT_GE(r.trials[0].goals.size(), 2u);
  r.trials.resize(1);
  r.trials[0].goals[1] = std::numeric_limits<double>::quiet_NaN();
  const std::string csv = tune::trials_csv(r);
  EXPECT_EQ(csv.find("–"), std::string::npos) << csv;
  std::istringstream in(csv);
  std::string header, row;
  std::getline(in, header);
  std::getline(in, row);
  std::vector<std::string> names, cells;
  std::istringstream h(header), c(row);
  for (std::string x; std::getline(h, x, ',');) names.push_back(x);
  for (std::string x; std::getline(c, x, ',');) cells.push_back(x);
  cells.resize(names.size());  // a trailing empty cell
  const auto at = std::find_if(names.begin(), names.end(),
                               [](const std::string& n) { return n.rfind("goal1_", 0) == 0; });
  ASSERT_NE(at, names.end()) << header;
  EXPECT_EQ(cells[static_cast<std::size_t>(at - names.begin())], "") << row;
  EXPECT_EQ(std::stod(cells[static_cast<std::size_t>(at - names.begin()) - 1]),
            r.trials[0].goals[0]);  // goal 0 beside it is a number
}

TEST(TuningRun, ResumedRunGivesTheSameGainsFileAndTrials) {
  const tune::Job job = short_job();
  const tune::TuningOutcome whole = tuned(job, 2);
  const std::string uninterrupted = tune::gains_document(whole).dump();
  std::string checkpoint;
  tune::RunOptions stop;
  stop.observer = [&](const tune::HistoryRow& h, const tune::Optimizer& o,
                      const std::vector<tune::Trial>& trials) {
    checkpoint = tune::run_checkpoint(o, trials).dump();
    return h.iteration < 1;
  };
  const tune::TuningOutcome partial = tuned(job, 1, std::nullopt, stop);
  EXPECT_FALSE(partial.completed());
  EXPECT_TRUE(partial.comparison.empty());
  const json state = json::parse(checkpoint);
  tune::RunOptions resume;
  resume.resume = &state;
  const tune::TuningOutcome resumed = tuned(job, 2, std::nullopt, resume);
  EXPECT_EQ(tune::gains_document(resumed).dump(), uninterrupted);
  // Every trial, those before the checkpoint included, with "best so far" counted across it.
  EXPECT_EQ(tune::trials_csv(resumed), tune::trials_csv(whole));
  EXPECT_GT(whole.trials.size(), partial.trials.size());

  // A bare optimiser state (what service stores written before trials were kept) still resumes,
  // with the trials since the resume.
  const json bare = state["optimizer"];
  resume.resume = &bare;
  const tune::TuningOutcome from_bare = tuned(job, 2, std::nullopt, resume);
  EXPECT_EQ(tune::gains_document(from_bare).dump(), uninterrupted);
  EXPECT_EQ(from_bare.trials.size(), whole.trials.size() - partial.trials.size());

  json broken = state;
  broken["trials"][0] = "not a trial";
  resume.resume = &broken;
  try {
    tuned(job, 2, std::nullopt, resume);
    ADD_FAILURE() << "a damaged checkpoint resumed";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("/trials"), std::string::npos) << e.what();
  }
}

TEST(Cli, EnsembleRunGivesTheSameGainsFileOnOneAndTwoThreads) {
  const auto dir = fresh_dir("run-ensemble");
  tune::write_file_atomic(dir / "job.json", short_ensemble_job().dump(2));
  const std::string job = std::string("'").append((dir / "job.json").string()).append("'");
  const CliResult a =
      run_cli("run " + job + " --threads 1 --out '" + (dir / "t1").string() + "'", dir);
  ASSERT_EQ(a.exit_code, 0) << a.err;
  EXPECT_NE(a.out.find("over 7 scenarios: 1 listed, 6 ensemble members;"), std::string::npos)
      << a.out;
  EXPECT_NE(a.out.find("noise floor"), std::string::npos) << a.out;
  const CliResult b =
      run_cli("run " + job + " --threads 2 -q --out '" + (dir / "t2").string() + "'", dir);
  ASSERT_EQ(b.exit_code, 0) << b.err;
  EXPECT_EQ(slurp(dir / "t1" / "gains.json"), slurp(dir / "t2" / "gains.json"));
  const json g = json::parse(slurp(dir / "t1" / "gains.json"));
  EXPECT_TRUE(g.contains("noise_floor"));
  const std::string md = slurp(dir / "t1" / "comparison.md");
  EXPECT_NE(md.find("## All 7 scenarios (1 listed, 6 ensemble members, seed 7)"), std::string::npos)
      << md;
  EXPECT_NE(md.find("noise floor"), std::string::npos);
}

TEST(TuningRun, RefusesAJobWhoseEveryScenarioIsUnrecoverable) {
  json j = short_ensemble_job();
  j["scenarios"][0]["faults"] = json::parse(
      R"([{"actuator": 1, "type": "stuck", "onset": 3, "value": 0},
          {"actuator": 2, "type": "stuck", "onset": 3, "value": 0}])");
  j["ensemble"]["faults"]["count"] = {2, 2};
  j["ensemble"]["faults"]["type"] = {{"stuck", 1}};
  tune::SerialEvaluator serial;
  try {
    tune::tune(tune::parse_job(j, "x"), serial);
    FAIL() << "tuned a job with nothing to improve";
  } catch (const InputError& e) {
    EXPECT_EQ(e.errors().at(0).path, "/ensemble/unrecoverable");
  }
  // Without an ensemble there is no policy to point at: the refusal names the scenario.
  j.erase("ensemble");
  try {
    tune::tune(tune::parse_job(j, "x"), serial);
    FAIL() << "tuned a job with nothing to improve";
  } catch (const InputError& e) {
    EXPECT_EQ(e.errors().at(0).path, "/scenarios/0");
    const std::string name = j["scenarios"][0]["name"];
    EXPECT_NE(e.errors().at(0).message.find("the only scenario (\"" + name + "\") is unrecoverable"),
              std::string::npos)
        << e.errors().at(0).message;
  }
}

// A rigid body's run that leaves the Euler angles' validity is reported as such by `run` too:
// comparison.json flags the listed scenario for every controller whose run left it, and the
// tuned gains' warnings (gains.json, the log, report.html) say so. A run that stays within it is
// flagged false, and a plant whose model holds everywhere has no flag at all.
TEST(TuningRun, SaysWhichRunsLeftTheModelsValidity) {
  std::ifstream in(std::string(FTC_SOURCE_DIR) + "/jobs/smallsat-pyramid.json");
  json j = json::parse(in);
  j["name"] = "steep";
  // Pitching up at 0.6 rad/s from 1.2 rad, which the wheels cannot stop before 85° (about
  // 0.5 s in; RigidBody.FlagsARunPastEightyFiveDegreesOfPitch); the second scenario stays level.
  j["scenarios"] = json::parse(R"([
    {"name": "steep", "duration": 0.6, "sample_time": 0.01,
     "initial_state": [0, 1.2, 0, 0, 0.6, 0]},
    {"name": "level", "duration": 0.6, "sample_time": 0.01,
     "initial_state": [0.02, -0.015, 0.01, 0, 0, 0]}])");
  j["objective"]["window"] = {0, 0.6};
  j["tuning"]["algorithm"] = {{"type", "random"}, {"population", 2}, {"iterations", 1}};
  tune::SerialEvaluator serial;
  const tune::TuningOutcome r = tune::tune(tune::parse_job(j, "x"), serial);
  const json doc = tune::comparison_document(r);
  ASSERT_EQ(doc["controllers"].size(), 3u) << doc.dump();
  for (const json& c : doc["controllers"]) {
    EXPECT_EQ(c["scenarios"][0].value("model_invalid", false), true) << c.dump();
    EXPECT_EQ(c["scenarios"][1].value("model_invalid", true), false) << c.dump();
  }
  const auto warned = std::count_if(r.warnings.begin(), r.warnings.end(), [](const auto& w) {
    return w.find("scenario steep: with the") != std::string::npos &&
           w.find("the pitch angle passed ±85°") != std::string::npos;
  });
  EXPECT_EQ(warned, 1) << ::testing::PrintToString(r.warnings);
  for (const std::string& w : r.warnings)
    EXPECT_FALSE(w.find("scenario level") != std::string::npos &&
                 w.find("±85°") != std::string::npos)
        << w;

  json sc = short_table1_job();
  sc["tuning"]["algorithm"]["iterations"] = 1;
  const tune::TuningOutcome plain = tune::tune(tune::parse_job(sc, "x"), serial);
  // (The document is kept: a range over a member of a temporary reads freed memory.)
  const json plain_doc = tune::comparison_document(plain);
  for (const json& c : plain_doc["controllers"])
    EXPECT_FALSE(c["scenarios"][0].contains("model_invalid")) << c.dump();
}

// A loop that failed is not a plain success. Wheels limited to 0.2 N·m with wheel 1 stuck at
// its limit from 2 s: the attitude drifts off whatever the gains (to |X1| of about 70 rad by
// 30 s in the full-length job). The run still finishes and writes its gains; its warnings say
// that the loop does not hold the vehicle, and that its commands sat at their limits. Neither the
// unlimited job's run nor one whose only saturated command is a stuck wheel's while the attitude
// holds (smallsat-pyramid's stuck-wheel scenario) is warned of.
TEST(TuningRun, WarnsWhenTheTunedLoopEndsFartherThanItStarted) {
  json j = short_table1_job();
  j["scenarios"][0]["saturation"] = 0.2;
  j["scenarios"][0]["faults"] =
      json::parse(R"([{"actuator": 1, "type": "stuck", "value": 0.2, "onset": 2}])");
  j["tuning"]["algorithm"]["iterations"] = 1;
  tune::SerialEvaluator serial;
  const tune::TuningOutcome r = tune::tune(tune::parse_job(j, "x"), serial);
  const auto has = [](const std::vector<std::string>& ws, const std::string& what) {
    return std::any_of(ws.begin(), ws.end(),
                       [&](const std::string& w) { return w.find(what) != std::string::npos; });
  };
  EXPECT_TRUE(has(r.warnings, "scenario paper: the tuned PI-FOSMC loop ends farther from the "
                              "reference than it started (|X1| = "))
      << ::testing::PrintToString(r.warnings);
  EXPECT_TRUE(has(r.warnings, "; its commands were at or beyond their limits on 100 % of the "
                              "samples of the objective window): it does not hold the vehicle"))
      << ::testing::PrintToString(r.warnings);
  // The job's metrics block sets the checks: a drift allowance above where the loop ends
  // silences that warning; with a settling threshold, a loop that never gets below it after the
  // fault is warned of.
  j["metrics"] = {{"drift_warning", 1e6}, {"settling_threshold", 0.01}};
  const tune::TuningOutcome quiet = tune::tune(tune::parse_job(j, "x"), serial);
  EXPECT_FALSE(has(quiet.warnings, "ends farther")) << ::testing::PrintToString(quiet.warnings);
  EXPECT_TRUE(has(quiet.warnings, "scenario paper: the tuned PI-FOSMC loop never settles after "
                                  "the fault: ‖e‖ is not below the settling threshold of 0.01 rad "
                                  "(metrics.settling_threshold) at the end of the objective "
                                  "window [0 s, 5 s)"))
      << ::testing::PrintToString(quiet.warnings);

  json plain = short_table1_job();
  plain["tuning"]["algorithm"]["iterations"] = 1;
  plain["metrics"] = {{"settling_threshold", 0.01}};  // the paper's loop settles well below it
  const tune::TuningOutcome p = tune::tune(tune::parse_job(plain, "x"), serial);
  EXPECT_FALSE(has(p.warnings, "ends farther")) << ::testing::PrintToString(p.warnings);
  EXPECT_FALSE(has(p.warnings, "never settles")) << ::testing::PrintToString(p.warnings);

  std::ifstream in(std::string(FTC_SOURCE_DIR) + "/jobs/smallsat-pyramid.json");
  json sat = json::parse(in);
  sat["scenarios"].erase(1);
  sat["scenarios"][0]["duration"] = 20;
  sat["objective"]["window"] = {5, 20};
  // Near the job's own gains, which hold the attitude (a short search elsewhere need not).
  sat["tuning"]["parameters"] = {{"Kp", {0.49, 0.51}}};
  sat["tuning"]["algorithm"]["population"] = 3;
  sat["tuning"]["algorithm"]["iterations"] = 1;
  const tune::TuningOutcome s = tune::tune(tune::parse_job(sat, "x"), serial);
  EXPECT_GT(s.comparison.back().outcome.evaluation.scenarios.at(0).errors.saturation_fraction, 0.9);
  EXPECT_FALSE(has(s.warnings, "ends farther")) << ::testing::PrintToString(s.warnings);
}

TEST(TuningRun, WarnsOfTunedValuesAtABound) {
  json j = short_table1_job();
  j["tuning"]["parameters"] = {{"Kp", {1, 50}},
                               {"Ki", {0, 50}},
                               {"switching_gain", {{"bounds", {2, 200}}, {"scale", "log"}}}};
  const tune::Job job = tune::parse_job(j, "x");
  // Field order: switching_gain, Kp, Ki.
  EXPECT_TRUE(tune::bound_warnings(job, {20, 25, 25}).empty());
  EXPECT_TRUE(tune::bound_warnings(job, {20, 1.1, 25}).empty());  // 0.2 % of the range away
  std::vector<std::string> w = tune::bound_warnings(job, {20, 25, 50});
  ASSERT_EQ(w.size(), 1u);
  EXPECT_NE(w[0].find("Ki = 50 ended at its upper bound 50"), std::string::npos) << w[0];
  EXPECT_NE(w[0].find("widen tuning.parameters.Ki"), std::string::npos) << w[0];
  // Ki cannot go below 0: no advice to widen.
  w = tune::bound_warnings(job, {20, 25, 0});
  ASSERT_EQ(w.size(), 1u);
  EXPECT_NE(w[0].find("the field's own limit"), std::string::npos) << w[0];
  // On a log scale the distance is measured in ln x: 199.5 is 0.05 % of ln(100) from 200.
  w = tune::bound_warnings(job, {199.5, 25, 25});
  ASSERT_EQ(w.size(), 1u);
  EXPECT_NE(w[0].find("switching_gain"), std::string::npos);
  EXPECT_TRUE(tune::bound_warnings(job, {190, 25, 25}).empty());
  // Told how much the objective changes 1 % of the range inward: within the noise floor the
  // objective is flat there and widening is not advised; beyond it, the change is given.
  EXPECT_EQ(tune::inward_value(job.tuning->parameters[2], 50).value(), 49.5);  // Ki in [0, 50]
  EXPECT_FALSE(tune::inward_value(job.tuning->parameters[2], 25));
  w = tune::bound_warnings(job, {20, 25, 50}, {std::nullopt, std::nullopt, 1e-6}, 2e-6);
  ASSERT_EQ(w.size(), 1u);
  EXPECT_NE(w[0].find("Ki = 50 ended at its upper bound 50 (within 0.1 % of the range), where the "
                      "objective is flat within the noise: 1 % of the range inward changes it by "
                      "0.0001 %, inside the noise floor of 0.0002 %"),
            std::string::npos)
      << w[0];
  EXPECT_EQ(w[0].find("widen tuning"), std::string::npos) << w[0];
  w = tune::bound_warnings(job, {20, 25, 50}, {std::nullopt, std::nullopt, 3e-6}, 2e-6);
  ASSERT_EQ(w.size(), 1u);
  EXPECT_NE(w[0].find("widen tuning.parameters.Ki and run again. (1 % of the range inward "
                      "changes the objective by 0.0003 %, beyond the noise floor of 0.0002 %.)"),
            std::string::npos)
      << w[0];
  // An open range: alpha2 < 1, so a bound at 0.7 can move, one at the top of the range cannot.
  j["tuning"]["parameters"] = {{"alpha2", {0.3, 0.7}}};
  w = tune::bound_warnings(tune::parse_job(j, "x"), {0.7});
  ASSERT_EQ(w.size(), 1u);
  EXPECT_NE(w[0].find("widen tuning.parameters.alpha2"), std::string::npos) << w[0];
}

TEST(Cli, Table1RunWarnsThatKiEndsOnItsBound) {
  const auto dir = fresh_dir("run-bound");
  const CliResult r = run_cli("run jobs/table1.json --out '" + (dir / "t").string() + "'", dir);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("[warning] Ki = 50 ended at its upper bound 50"), std::string::npos)
      << r.err;
  // Seven digits, not J alone, labelled with the metric and its window.
  EXPECT_NE(r.out.find("ISE[0 s, 30 s] = 1.33"), std::string::npos) << r.out;
  // The job's own controller against the tuned one, relative to the tuned objective as the
  // noise-floor sentence gives it: the two figures are one.
  const std::size_t above = r.out.find(" % above the tuned)");
  ASSERT_NE(above, std::string::npos) << r.out;
  const std::string percent = r.out.substr(r.out.rfind(", ", above) + 2,
                                           above - r.out.rfind(", ", above) - 2);
  EXPECT_NE(r.out.find("objective is " + percent + " % above the tuned one's"), std::string::npos)
      << r.out;
  // NFTSMC's ISE is lower than the tuned PI-FOSMC's: the run says so rather than call its gains
  // optimal.
  EXPECT_NE(r.err.find("[warning] NFTSMC (compared) scores ISE[0 s, 30 s] = 0.902"), std::string::npos)
      << r.err;
  const json g = json::parse(slurp(dir / "t" / "gains.json"));
  ASSERT_EQ(g["warnings"].size(), 2u);
  // Ki on its bound, where the objective is flat within the noise: no advice to widen.
  EXPECT_NE(g["warnings"][0].get<std::string>().find(
                "where the objective is flat within the noise: 1 % of the range inward changes it "
                "by "),
            std::string::npos)
      << g["warnings"][0];
  EXPECT_EQ(g["warnings"][0].get<std::string>().find("widen tuning"), std::string::npos);
  EXPECT_NE(g["warnings"][1].get<std::string>().find("below the tuned PI-FOSMC's 1.332"),
            std::string::npos)
      << g["warnings"][1];
  EXPECT_EQ(slurp(dir / "t" / "comparison.md").find("optimal"), std::string::npos);
}

TEST(TuningRun, ObjectiveLabelNamesTheMetricTheWindowAndTheAggregate) {
  json j = short_table1_job();
  EXPECT_EQ(tune::objective_label(tune::parse_job(j, "x")), "ISE[0 s, 5 s]");
  j["objective"] = {{"metric", "itae"}, {"window", {1.5, 4}}};
  EXPECT_EQ(tune::objective_label(tune::parse_job(j, "x")), "ITAE[1.5 s, 4 s]");
  json e = short_ensemble_job();  // CVaR 0.9 over 8 s after the first fault, 6 members + 1
  e["objective"]["window"] = {0, 8};
  EXPECT_EQ(tune::objective_label(tune::parse_job(e, "x")),
            "CVaR0.9 of ISE[first fault, +8 s] over 7 scenarios");
  e["objective"] = {{"metric", "iae"},
                    {"window", {1, 4}},
                    {"window_from", "first_fault"},
                    {"aggregate", "quantile"},
                    {"q", 0.75}};
  EXPECT_EQ(tune::objective_label(tune::parse_job(e, "x")),
            "quantile0.75 of IAE[first fault + 1 s, +4 s] over 7 scenarios");
  e["objective"] = {{"metric", "ise"}, {"aggregate", "max"}};
  EXPECT_EQ(tune::objective_label(tune::parse_job(e, "x")),
            "max of ISE[0 s, end] over 7 scenarios");
}

TEST(TuningRun, WarnsWhenAComparedControllerScoresLowerOrTheTunedGainsChatter) {
  tune::TuningOutcome r = tuned(short_job(), 2);
  ASSERT_EQ(r.comparison.size(), 4u);  // NFTSMC, FOSMC, the job's, the tuned
  const auto set = [&](std::size_t c, double objective, double tv) {
    r.comparison[c].outcome.evaluation.objective = objective;
    r.comparison[c].outcome.evaluation.scenarios.at(0).control_tv = tv;
  };
  r.noise_floor->relative_spread = 0.01;
  set(0, 2.0, 100);
  set(1, 3.0, 100);
  set(2, 2.5, 100);
  set(3, 1.0, 299);
  EXPECT_TRUE(tune::comparison_warnings(r).empty());
  set(0, 0.995, 100);  // inside the noise floor of 1 %
  set(3, 1.0, 301);    // 3.01 times the job's own
  std::vector<std::string> w = tune::comparison_warnings(r);
  ASSERT_EQ(w.size(), 2u);
  EXPECT_NE(w[0].find("NFTSMC (compared) scores ISE[0 s, 5 s] = 0.995, 0.5 % below the tuned PI-FOSMC's 1 "
                      "(inside the noise floor of 1 %)"),
            std::string::npos)
      << w[0];
  EXPECT_NE(w[1].find("raise the control TV (sum of |u_k - u_{k-1}|, a measure of chattering) "
                      "3.01 times over the job's own gains"),
            std::string::npos)
      << w[1];
  // One that breaks a hard goal is not the better controller, whatever it scores.
  r.comparison[0].outcome.evaluation.violation = 0.5;
  w = tune::comparison_warnings(r);
  ASSERT_EQ(w.size(), 1u) << ::testing::PrintToString(w);
  EXPECT_EQ(w[0].find("NFTSMC"), std::string::npos) << w[0];
  r.comparison[0].outcome.evaluation.violation = 0;
  set(1, 0.5, 100);
  w = tune::comparison_warnings(r);
  ASSERT_EQ(w.size(), 3u);
  EXPECT_NE(w[1].find("FOSMC (compared) scores ISE[0 s, 5 s] = 0.5, 50 % below the tuned PI-FOSMC's 1 "
                      "(beyond the noise floor"),
            std::string::npos)
      << w[1];
  // The job's metrics block moves the control-TV bar: 3.01 times is within 4.
  tune::MetricsConfig m;
  m.control_tv_warning = 4.0;
  r.job.metrics = m;
  w = tune::comparison_warnings(r);
  EXPECT_EQ(w.size(), 2u) << ::testing::PrintToString(w);
  for (const std::string& x : w) EXPECT_EQ(x.find("control TV"), std::string::npos) << x;
  // A job with a goal on the control TV prices it (issue 41): the warning does not say that it
  // does not; a hard goal caps it, and nothing is said.
  r.job.metrics.reset();
  tune::GoalConfig tv_goal;
  tv_goal.metric = &sim::kMetricFields[sim::metric_index("control_tv")];
  tv_goal.minimize = true;
  r.job.goals = {tune::GoalConfig{}, tv_goal};
  r.job.goals[0].minimize = true;
  w = tune::comparison_warnings(r);
  ASSERT_EQ(w.size(), 3u) << ::testing::PrintToString(w);
  EXPECT_NE(w[2].find("3.01 times over the job's own gains"), std::string::npos) << w[2];
  EXPECT_NE(w[2].find("the job minimizes the control TV as a goal, so this is a trade-off its "
                      "goals chose"),
            std::string::npos)
      << w[2];
  EXPECT_EQ(w[2].find("does not price"), std::string::npos) << w[2];
  r.job.goals[1].minimize = false;
  r.job.goals[1].at_most = 1000;
  w = tune::comparison_warnings(r);
  EXPECT_EQ(w.size(), 2u) << ::testing::PrintToString(w);
  for (const std::string& x : w) EXPECT_EQ(x.find("control TV"), std::string::npos) << x;
}

TEST(Cli, RunNeverWritesSilentlyOverAnEarlierRun) {
  const auto dir = fresh_dir("run-overwrite");
  json j = short_table1_job();
  j["name"] = "overwrite-test-" + std::to_string(::getpid());
  tune::write_file_atomic(dir / "job.json", j.dump());
  const std::string job = "'" + (dir / "job.json").string() + "'";
  const std::string out = (dir / "run").string();
  ASSERT_EQ(run_cli("run " + job + " -q --out '" + out + "'", dir).exit_code, 0);
  const std::string first = slurp(dir / "run" / "gains.json");
  // A given --out that holds files is refused, and nothing in it changes.
  tune::write_file_atomic(dir / "run" / "figures" / "stale.png", "old");
  CliResult r = run_cli("run " + job + " -q --seed 7 --out '" + out + "'", dir);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("already holds a run"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("--force"), std::string::npos) << r.err;
  EXPECT_EQ(slurp(dir / "run" / "gains.json"), first);
  // --force replaces the run, and what the earlier run left (its figures) is gone.
  r = run_cli("run " + job + " -q --seed 7 --force --out '" + out + "'", dir);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(slurp(dir / "run" / "gains.json"), first);
  EXPECT_FALSE(std::filesystem::exists(dir / "run" / "figures" / "stale.png"));
  // Without --out, the default out/<name> moves on to out/<name>-2 (run from a scratch working
  // directory, so nothing lands in the source tree); files that are not a run do not count.
  const auto cwd = fresh_dir("run-default");
  const auto run_here = [&](const std::string& args) {
    return std::system(
        ("cd '" + cwd.string() + "' && '" FTC_CLI "' " + args + " >/dev/null 2>&1").c_str());
  };
  const std::string name = j["name"];
  tune::write_file_atomic(cwd / "out" / name / "simulate" / "metrics.json", "{}");
  ASSERT_EQ(run_here("run " + job + " -q"), 0);
  EXPECT_TRUE(std::filesystem::exists(cwd / "out" / name / "gains.json"));
  ASSERT_EQ(run_here("run " + job + " -q"), 0);
  EXPECT_TRUE(std::filesystem::exists(cwd / "out" / (name + "-2") / "gains.json"));
  // The run's file list and the trials table.
  const json run = json::parse(slurp(cwd / "out" / name / "run.json"));
  EXPECT_NE(std::find(run["files"].begin(), run["files"].end(), "trials.csv"), run["files"].end());
  std::istringstream trials(slurp(cwd / "out" / name / "trials.csv"));
  std::string line;
  std::getline(trials, line);
  EXPECT_EQ(line,
            "iteration,index,Kp,Ki,objective,fitness,diverged,accepted,capped,simulated,cached,"
            "objective_paper");
  int rows = 0, accepted = 0;
  while (std::getline(trials, line)) {
    ++rows;
    std::vector<std::string> cells;
    std::stringstream cs(line);
    for (std::string c; std::getline(cs, c, ',');) cells.push_back(c);
    ASSERT_EQ(cells.size(), 12u) << line;
    accepted += cells[7] == "1";
    // One scenario: nothing to cap; every trial simulated it but those the cache served.
    EXPECT_EQ(cells[8], "0") << line;
    EXPECT_EQ(cells[9], cells[10] == "1" ? "0" : "1") << line;
  }
  EXPECT_EQ(rows, 9);  // 3 bats x (1 + 2 iterations): one row per evaluation
  EXPECT_GE(accepted, 1);
}

// The shipped Table 1 and post-fault jobs tune to the bits c418505 gave (its gains files'
// fitness, objective and tuned gains, as hexadecimal floats), through the one closed loop that
// now serves every plant (issue 25). robust-faults.json, the third job the issue names, takes
// 44 s, too long for the suite: its gains file was compared byte for byte when the kernel
// changed. Every instruction set gives these bits (BatchKernel.*).
TEST(TuningRun, ShippedJobsTuneToTheBitsOfBeforeTheOneKernel) {
  struct Expected {
    const char* job;
    double fitness, objective, Kp, Ki;
  };
  const Expected expected[] = {
      {"table1.json", 0x1.8066552427e43p-1, 0x1.54fa7733750afp+0, 0x1.48063497c8c63p+0,
       0x1.9000000000000p+5},
      {"post-fault.json", 0x1.0224a9cf12939p+22, 0x1.fbbfc8aa23688p-23, 0x1.0000000000000p+0,
       0x1.8f785bdd63586p+5}};
  for (const Expected& e : expected) {
    std::ifstream in(std::string(FTC_SOURCE_DIR) + "/jobs/" + e.job);
    const json doc = tune::gains_document(tuned(tune::parse_job(json::parse(in), e.job), 2));
    EXPECT_EQ(doc["fitness"].get<double>(), e.fitness) << e.job;
    EXPECT_EQ(doc["objective"]["value"].get<double>(), e.objective) << e.job;
    EXPECT_EQ(doc["controller"]["Kp"].get<double>(), e.Kp) << e.job;
    EXPECT_EQ(doc["controller"]["Ki"].get<double>(), e.Ki) << e.job;
  }
}

TEST(TuningRun, HardGoalIsMetByTheWinnerOfEveryOptimiser) {
  // The short Table 1 job with a soft ISE goal and a hard goal on the control TV. The limit is
  // the median TV of the initial population (the same for any limit: the seed draws it), so
  // that it is met by some candidates and not by others.
  json j = short_table1_job();
  j.erase("objective");
  j["goals"] = {{{"metric", "ise"}, {"window", {0, 5}}, {"minimize", true}},
                {{"metric", "control_tv"}, {"aggregate", "max"}, {"at_most", 1e300}}};
  const tune::TuningOutcome loose = tuned(tune::parse_job(j, "loose"), 2);
  std::vector<double> tv;
  for (const tune::Trial& t : loose.trials) {
    ASSERT_EQ(t.goals.size(), 2u);
    EXPECT_EQ(t.goals[0], t.objective);
    EXPECT_EQ(t.violation, 0.0);
    if (t.iteration == 0) tv.push_back(t.goals[1]);
  }
  std::sort(tv.begin(), tv.end());
  const double limit = tv[tv.size() / 2];
  j["goals"][1]["at_most"] = limit;
  const json algorithms[] = {
      j["tuning"]["algorithm"],
      {{"type", "random"}, {"population", 3}, {"iterations", 2}},
      {{"type", "pagmo"}, {"name", "pso_gen"}, {"population", 4}, {"generations", 2}}};
  for (const json& algorithm : algorithms) {
    j["tuning"]["algorithm"] = algorithm;
    const tune::TuningOutcome r = tuned(tune::parse_job(j, "capped"), 2);
    const std::string name = algorithm["type"].get<std::string>();
    const tune::Evaluation& won = r.best().outcome.evaluation;
    ASSERT_EQ(won.goals.size(), 2u) << name;
    EXPECT_LE(won.goals[1], limit) << name;
    EXPECT_TRUE(won.feasible()) << name;
    EXPECT_GE(r.optimization.best_fitness, 0.0) << name;
    // Every trial is scored by the rule, and some of each kind were seen.
    int feasible = 0, infeasible = 0;
    for (const tune::Trial& t : r.trials) {
      EXPECT_EQ(t.violation, std::max(0.0, t.goals[1] / limit - 1.0)) << name;
      if (t.violation > 0) {
        ++infeasible;
        EXPECT_LT(t.fitness, 0.0) << name;
      } else {
        ++feasible;
        EXPECT_GE(t.fitness, 0.0) << name;
        EXPECT_GE(r.optimization.best_fitness, t.fitness) << name;  // the best feasible won
      }
    }
    EXPECT_GT(feasible, 0) << name;
    EXPECT_GT(infeasible, 0) << name;
    // trials.csv carries the goals, the violation and feasibility; gains.json the goals.
    const std::string csv = tune::trials_csv(r);
    EXPECT_NE(csv.find(",goal0_ise,goal1_control_tv,violation,feasible\n"), std::string::npos);
    const json gains = tune::gains_document(r);
    EXPECT_EQ(gains["goals"]["feasible"], true);
    EXPECT_EQ(gains["goals"]["goals"][1]["at_most"], limit);
  }
}

namespace {

// The short Table 1 job scored by a soft ISE goal under a limit on the control TV.
json capped_short_job(double limit) {
  json j = short_table1_job();
  j.erase("objective");
  j["goals"] = {{{"metric", "ise"}, {"window", {0, 5}}, {"minimize", true}},
                {{"metric", "control_tv"}, {"at_most", limit}}};
  return j;
}

}  // namespace

TEST(TuningRun, ResumedConstrainedRunKeepsTheGoalsOfEveryTrial) {
  // A limit (100) under every candidate's TV on this job (about 250): every trial is
  // infeasible, so the resumed run must carry each trial's violation across the checkpoint.
  const tune::Job job = tune::parse_job(capped_short_job(100), "capped");
  const tune::TuningOutcome whole = tuned(job, 2);
  for (const tune::Trial& t : whole.trials) ASSERT_GT(t.violation, 0.0);
  const json state = checkpoint_after(job, 1);
  expect_resumed_run_writes_the_same(job, state, whole);
  EXPECT_EQ(tune::gains_document(whole)["goals"]["feasible"], false);
}

TEST(Cli, RunExitsTwoForAFrontOfAnAlgorithmOfOneObjectiveAndThreeWhenNoCandidateMeetsTheLimits) {
  const auto dir = fresh_dir("goals");
  const auto run = [&](const json& j) {
    {
      std::ofstream f(dir / "job.json");
      f << j.dump();
    }
    return run_cli("run --force --no-checkpoint --threads 1 '" + (dir / "job.json").string() +
                       "' --out '" + (dir / "out").string() + "'",
                   dir);
  };
  json pareto = capped_short_job(100);
  pareto["goals"][1] = {{"metric", "control_tv"}, {"minimize", true}};
  pareto["tuning"]["algorithm"] = {{"type", "pagmo"}, {"name", "sade"},
                                   {"population", 7}, {"generations", 1}};
  const CliResult two = run(pareto);
  EXPECT_EQ(two.exit_code, 2);
  EXPECT_NE(two.err.find("Pareto front"), std::string::npos) << two.err;
  const CliResult none = run(capped_short_job(100));
  EXPECT_EQ(none.exit_code, 3);
  EXPECT_NE(none.err.find("no candidate met the job's hard goals"), std::string::npos) << none.err;
}

namespace {

// A job run twice with a switch of RunOptions off, then on: the outcomes, and the optimiser's
// state after every iteration of each.
struct TwoRuns {
  tune::TuningOutcome runs[2];
  std::vector<std::string> states[2];
};
TwoRuns run_with_and_without(const tune::Job& job, int threads, bool tune::RunOptions::*option,
                             const tune::RunOptions& base = {}) {
  TwoRuns r;
  for (const bool on : {false, true}) {
    tune::RunOptions o = base;
    o.*option = on;
    o.observer = [&](const tune::HistoryRow&, const tune::Optimizer& opt,
                     const std::vector<tune::Trial>&) {
      r.states[on].push_back(opt.state().dump());
      return true;
    };
    r.runs[on] = tuned(job, threads, std::nullopt, o);
  }
  return r;
}

// A job run with capping on and off (issue 27), on 1 and 2 threads: the capped trials and the
// trials.csv of the capped run on 2 threads, and the feasibility of the uncapped trials.
struct CappingComparison {
  std::vector<tune::Trial> capped;
  std::string csv;
  int feasible = 0, infeasible = 0;
};

// Runs the job with capping on and off and checks what must hold: the same gains file, history
// and optimiser state after every iteration; the same trial wherever it was not capped; a capped
// trial stopped early, never became the best, and its objective, goals (NaN: no bound) and
// violation are at most the true ones, its fitness at least; the capped run's trials.csv (where
// each candidate stopped) is the same for 1 and 2 threads, and it simulated less.
CappingComparison compare_capping(const json& j, const std::string& algorithm) {
  CappingComparison r;
  std::string one_thread;
  const tune::Job job = tune::parse_job(j, "x");
  for (const int threads : {1, 2}) {
    // Capping alone: with the cache a candidate capped once and proposed again runs again,
    // while without capping the cache serves it (TuningRun.CacheChangesNoFileButTrialsCsv has
    // both).
    tune::RunOptions no_cache;
    no_cache.cache = false;
    const TwoRuns two = run_with_and_without(job, threads, &tune::RunOptions::capping, no_cache);
    const auto& states = two.states;
    const tune::TuningOutcome& off = two.runs[0];
    const tune::TuningOutcome& on = two.runs[1];
    EXPECT_EQ(tune::gains_document(on).dump(), tune::gains_document(off).dump()) << algorithm;
    EXPECT_EQ(tune::history_csv(on), tune::history_csv(off)) << algorithm;
    EXPECT_EQ(states[1], states[0]) << algorithm;
    EXPECT_LT(on.simulations, off.simulations) << algorithm;
    EXPECT_EQ(on.trials.size(), off.trials.size());
    r = CappingComparison{};
    for (std::size_t i = 0; i < on.trials.size() && i < off.trials.size(); ++i) {
      const tune::Trial& a = on.trials[i];
      const tune::Trial& b = off.trials[i];
      (b.violation > 0 ? r.infeasible : r.feasible) += 1;
      if (!a.capped) {
        EXPECT_EQ(tune::trials_json(on.trials, i)[0], tune::trials_json(off.trials, i)[0]) << i;
        continue;
      }
      r.capped.push_back(a);
      EXPECT_FALSE(b.capped);
      EXPECT_LT(a.simulated, on.scenarios);
      EXPECT_LE(a.objective, b.objective) << i;
      EXPECT_GE(a.fitness, b.fitness) << i;
      EXPECT_LE(a.violation, b.violation) << i;
      EXPECT_EQ(a.goals.size(), b.goals.size());
      for (std::size_t k = 0; k < a.goals.size() && k < b.goals.size(); ++k)
        if (!std::isnan(a.goals[k])) {
          EXPECT_LE(a.goals[k], b.goals[k]) << i << " " << k;
        }
      EXPECT_FALSE(b.accepted) << "a capped candidate became the best: " << i;
      EXPECT_EQ(a.parameters, b.parameters);
    }
    EXPECT_EQ(on.front.has_value(), off.front.has_value()) << algorithm;
    if (on.front && off.front) {  // a job of a front: front.json and front.csv too
      EXPECT_EQ(tune::front_document(job, "", 1, *on.front).dump(),
                tune::front_document(job, "", 1, *off.front).dump())
          << algorithm;
      EXPECT_EQ(tune::front_csv(job, *on.front), tune::front_csv(job, *off.front)) << algorithm;
      EXPECT_EQ(on.hypervolume, off.hypervolume) << algorithm;
    }
    const std::string csv = tune::trials_csv(on);
    if (threads == 2) {
      EXPECT_EQ(csv, one_thread) << algorithm << ": where stops depend on threads";
    }
    one_thread = csv;
    r.csv = csv;
  }
  return r;
}

}  // namespace

// Capping (issue 27): with capping on and off a run writes the same gains file and history and
// checkpoints the same optimiser state after every iteration, for the Bat algorithm and random
// search, on 1 and 2 threads. trials.csv differs only in the capped trials' rows: a lower bound
// of the objective there, and the row of the same trial without capping never mattered.
TEST(TuningRun, CappingChangesNothingButTheCappedTrialsRows) {
  for (const char* algorithm : {"bat", "random"}) {
    json j = short_ensemble_job();
    j["ensemble"]["count"] = 11;
    j["tuning"]["algorithm"] = {{"type", algorithm}, {"population", 4}, {"iterations", 3}};
    const CappingComparison r = compare_capping(j, algorithm);
    EXPECT_FALSE(r.capped.empty()) << algorithm << ": nothing was capped, the test would prove nothing";
    // The columns: capped, simulated; a capped row says after how many scenarios it stopped.
    EXPECT_NE(r.csv.find(",accepted,capped,simulated,cached\n"), std::string::npos) << r.csv;
    EXPECT_NE(r.csv.find(",0,0,12,0\n"), std::string::npos) << r.csv;
  }
}

// Capping with goals (issue 27): a job of one soft goal and hard goals (limits on the largest
// control TV and the median peak command, which have lower bounds, and on the steady-state error,
// which has none) changes nothing but the capped trials' rows either, and some candidates stop
// on their limits. In trials.csv a capped row's goal without a bound is empty, and its
// feasibility too unless its violation's bound already exceeds 0.
TEST(TuningRun, CappingWithGoalsChangesNothingButTheCappedTrialsRows) {
  for (const char* algorithm : {"bat", "random"}) {
    // Limits of the short job's scale: met by some candidates, broken by others.
    json j = goal_ensemble_job(1000, 30, true);
    j["tuning"]["algorithm"] = {{"type", algorithm}, {"population", 4}, {"iterations", 3}};
    const CappingComparison r = compare_capping(j, algorithm);
    EXPECT_GT(r.feasible, 0) << algorithm;
    EXPECT_GT(r.infeasible, 0) << algorithm;
    EXPECT_FALSE(r.capped.empty()) << algorithm << ": nothing was capped, the test would prove nothing";
    int on_limits = 0;
    for (const tune::Trial& t : r.capped) {
      on_limits += t.violation > 0 ? 1 : 0;
      ASSERT_EQ(t.goals.size(), 4u);
      EXPECT_TRUE(std::isnan(t.goals[3])) << "steady_state_error has no lower bound";
    }
    EXPECT_GT(on_limits, 0) << algorithm << ": no candidate stopped on its limits";
    // A capped row: capped 1, the members it ran, cached 0, the goals' bounds (the steady-state
    // error's empty), the violation's bound and feasible 0 (broken) or empty (not known).
    EXPECT_TRUE(
        std::regex_search(r.csv, std::regex(",1,[0-9]+,0,[^,\n]+,[^,\n]+,[^,\n]+,,[^,\n]+,0\n")))
        << r.csv;
  }
}

// Capping of fronts (issue 42): the Pareto Bat (on its FrontCap rules) and random search (on the
// run's front) stop candidates, and the gains, history, front.json, front.csv, hypervolumes and
// optimiser states are the same bytes as without capping, on 1 and 2 threads.
TEST(TuningRun, CappingAFrontChangesNothingButTheCappedTrialsRows) {
  for (const char* algorithm : {"bat", "random"}) {
    json j = front_ensemble_job();
    j["tuning"]["algorithm"] = {{"type", algorithm}, {"population", 6}, {"iterations", 4}};
    const CappingComparison r = compare_capping(j, algorithm);
    EXPECT_FALSE(r.capped.empty())
        << algorithm << ": nothing was capped, the test would prove nothing";
    EXPECT_GT(r.feasible, 0) << algorithm;
  }
}

// A capped run stopped after an iteration and resumed writes the uninterrupted run's trials
// (the incumbent's values, which order the scenarios, are simulated again on resume).
TEST(TuningRun, ResumedCappedRunWritesTheSameTrials) {
  json objective = short_ensemble_job();
  objective["ensemble"]["count"] = 11;
  // A job with goals too: its capped rows carry the goals' bounds (null where none) across.
  // And a front's (issue 42): the run's front, which caps random search, is rebuilt from them.
  json front = front_ensemble_job();
  front["tuning"]["algorithm"] = {{"type", "random"}, {"population", 6}, {"iterations", 4}};
  json pareto = front_ensemble_job();
  pareto["tuning"]["algorithm"] = {{"type", "bat"}, {"population", 6}, {"iterations", 4}};
  for (json j : {objective, goal_ensemble_job(1000, 30, true), front, pareto}) {
    if (j["name"] != "front-ensemble")
      j["tuning"]["algorithm"] = {{"type", "bat"}, {"population", 4}, {"iterations", 3}};
    const tune::Job job = tune::parse_job(j, "x");
    const tune::TuningOutcome whole = tuned(job, 2);
    const json state = checkpoint_after(job, 2);
    // A capped row has one more element, a count: the 9th (11th with goals).
    bool any_capped = false;
    const std::size_t base = job.goals.empty() ? 8u : 10u;
    for (const json& row : state["trials"])
      any_capped = any_capped || (row.size() > base && row[base].is_number_unsigned());
    EXPECT_TRUE(any_capped) << "no capped trial before the checkpoint: the test proves less";
    expect_resumed_run_writes_the_same(job, state, whole);
  }
}

namespace {

// `ftctune run` of the job j (written to dir/job.json) into dir/on, then with `flag` into
// dir/off: both succeed and write the same gains.json and history.csv. Returns the first run.
CliResult run_with_and_without_flag(const std::filesystem::path& dir, const json& j,
                                    const std::string& flag) {
  tune::write_file_atomic(dir / "job.json", j.dump(2));
  const std::string job = std::string("'").append((dir / "job.json").string()).append("'");
  CliResult a = run_cli("run " + job + " --out '" + (dir / "on").string() + "'", dir);
  EXPECT_EQ(a.exit_code, 0) << a.err;
  const CliResult b =
      run_cli("run " + job + " -q " + flag + " --out '" + (dir / "off").string() + "'", dir);
  EXPECT_EQ(b.exit_code, 0) << b.err;
  EXPECT_EQ(slurp(dir / "on" / "gains.json"), slurp(dir / "off" / "gains.json"));
  EXPECT_EQ(slurp(dir / "on" / "history.csv"), slurp(dir / "off" / "history.csv"));
  return a;
}

}  // namespace

// `ftctune run --no-capping` simulates every candidate on every scenario: the same gains.json
// and history.csv as the default (capping), and no capped trial in its trials.csv.
TEST(Cli, RunWithoutCappingWritesTheSameGainsAndNoCappedTrial) {
  const auto dir = fresh_dir("run-no-capping");
  json j = short_ensemble_job();
  j["ensemble"]["count"] = 11;
  j["tuning"]["algorithm"] = {{"type", "bat"}, {"population", 4}, {"iterations", 3}};
  ASSERT_EQ(run_with_and_without_flag(dir, j, "--no-capping").exit_code, 0);
  // The capped column of every row (after objective, fitness, diverged, accepted).
  const auto capped_rows = [](const std::string& csv) {
    int n = 0;
    std::size_t at = csv.find('\n');
    while (at != std::string::npos && at + 1 < csv.size()) {
      const std::size_t end = csv.find('\n', at + 1);
      const std::string row = csv.substr(at + 1, end - at - 1);
      std::vector<std::string> cells;
      for (std::size_t p = 0, q; p <= row.size(); p = q + 1) {
        q = row.find(',', p);
        if (q == std::string::npos) q = row.size();
        cells.push_back(row.substr(p, q - p));
      }
      n += cells.size() > 9 && cells[9] == "1" ? 1 : 0;  // iteration, index, 3 parameters, ...
      at = end;
    }
    return n;
  };
  EXPECT_GT(capped_rows(slurp(dir / "on" / "trials.csv")), 0);
  EXPECT_EQ(capped_rows(slurp(dir / "off" / "trials.csv")), 0);
  EXPECT_GT(json::parse(slurp(dir / "off" / "run.json"))["simulations"].get<std::int64_t>(),
            json::parse(slurp(dir / "on" / "run.json"))["simulations"].get<std::int64_t>());
}

// The cache (issue 43): a decision vector proposed again is not simulated again. A batch of
// candidates x, y, x and then y, z: the fitness is the bits of the uncached evaluation's, the
// second x and the second y are copies of the first ones' trials (never accepted), and only three
// candidates were simulated.
TEST(ProblemFitness, ServesADecisionVectorProposedAgainFromItsFirstTrial) {
  const tune::TuningProblem problem(short_job());
  tune::TbbEvaluator evaluator(2);
  const tune::Decision x{2.0, 1.0}, y{3.0, 5.0}, z{4.0, 5.0};
  std::vector<double> fitness[2];
  std::int64_t simulations[2];
  std::vector<tune::Trial> trials[2];
  for (const bool cache : {false, true}) {
    tune::ProblemFitness f(problem, evaluator);
    f.set_cache(cache);
    fitness[cache] = f({x, y, x});
    for (double J : f({y, z})) fitness[cache].push_back(J);
    simulations[cache] = f.simulations();
    trials[cache] = f.trials();
    EXPECT_EQ(f.cached(), cache ? 2 : 0);
  }
  ASSERT_EQ(fitness[1].size(), 5u);
  for (std::size_t i = 0; i < 5; ++i)
    EXPECT_EQ(std::bit_cast<std::uint64_t>(fitness[1][i]),
              std::bit_cast<std::uint64_t>(fitness[0][i]))
        << i;
  EXPECT_EQ(simulations[0], 5);  // one scenario a candidate
  EXPECT_EQ(simulations[1], 3);
  const std::vector<bool> expected{false, false, true, true, false};
  for (std::size_t i = 0; i < 5; ++i) {
    const tune::Trial& on = trials[1][i];
    const tune::Trial& off = trials[0][i];
    EXPECT_EQ(on.cached, expected[i]) << i;
    EXPECT_FALSE(off.cached) << i;
    EXPECT_EQ(on.index, off.index) << i;
    EXPECT_EQ(on.parameters, off.parameters);
    EXPECT_EQ(on.objective, off.objective) << i;
    EXPECT_EQ(on.scenario_objectives, off.scenario_objectives) << i;
    EXPECT_EQ(on.accepted, off.accepted) << i;
    if (on.cached) {
      EXPECT_FALSE(on.accepted) << i;
    }
  }
}

// With capping (issue 43): duplicates of a batch run once with the least of their caps, so a
// candidate proposed twice, once with a cap that alone stops it and once without a cap, runs to
// the end and both rows get its exact results; a candidate capped earlier is simulated again
// when proposed again (its bound serves no other cap).
TEST(ProblemFitness, CappingRunsTheDuplicatesOfABatchWithTheLeastOfTheirCaps) {
  json j = short_ensemble_job();
  j["ensemble"]["count"] = 11;
  const tune::TuningProblem problem(tune::parse_job(j, "x"));
  tune::TbbEvaluator evaluator(2);
  tune::Decision x;  // the middle of the box, in search coordinates
  for (std::size_t k = 0; k < problem.space().lower.size(); ++k)
    x.push_back((problem.space().lower[k] + problem.space().upper[k]) / 2);
  const std::int64_t n = static_cast<std::int64_t>(problem.scenarios());
  double exact = 0;
  {
    tune::ProblemFitness f(problem, evaluator);
    f.set_cache(false);
    exact = f({x})[0];
  }
  // Far above any fitness: alone, it stops after its first round.
  const double cap = std::numeric_limits<double>::max();
  {
    tune::ProblemFitness alone(problem, evaluator);
    alone.evaluate_capped({x}, {cap});
    ASSERT_TRUE(alone.trials()[0].capped) << "not capped alone: the test would prove nothing";
    EXPECT_LT(alone.simulations(), n);
    // Proposed again with no cap: simulated again, in full.
    const std::vector<double> J = alone.evaluate_capped({x}, {tune::kNoCap});
    EXPECT_EQ(alone.cached(), 0);
    EXPECT_FALSE(alone.trials()[1].capped);
    EXPECT_FALSE(alone.trials()[1].cached);
    EXPECT_EQ(std::bit_cast<std::uint64_t>(J[0]), std::bit_cast<std::uint64_t>(exact));
  }
  tune::ProblemFitness f(problem, evaluator);
  const std::vector<double> J = f.evaluate_capped({x, x}, {cap, tune::kNoCap});
  EXPECT_EQ(f.simulations(), n);  // once, in full
  ASSERT_EQ(f.trials().size(), 2u);
  for (std::size_t i = 0; i < 2; ++i) {
    EXPECT_FALSE(f.trials()[i].capped) << i;
    EXPECT_EQ(std::bit_cast<std::uint64_t>(J[i]), std::bit_cast<std::uint64_t>(exact)) << i;
  }
  EXPECT_FALSE(f.trials()[0].cached);
  EXPECT_TRUE(f.trials()[1].cached);
}

namespace {

// Runs the job with the cache on and off, on 1 and 2 threads, and checks what must hold: the
// same gains file, history, front and optimiser state after every iteration; as many trials;
// a cached trial has the parameters of the uncached run's trial and, where neither is capped,
// its values to the bit; the cached run simulated less, and its trials.csv is the same for 1 and
// 2 threads. Returns the cached run's trials.csv on 2 threads.
std::string compare_cache(const json& j, const std::string& label) {
  const tune::Job job = tune::parse_job(j, "x");
  std::string one_thread;
  for (const int threads : {1, 2}) {
    const TwoRuns two = run_with_and_without(job, threads, &tune::RunOptions::cache);
    const auto& states = two.states;
    const tune::TuningOutcome& off = two.runs[0];
    const tune::TuningOutcome& on = two.runs[1];
    EXPECT_GT(tune::cached_trials(on.trials), 0)
        << label << ": nothing was cached, the test would prove nothing";
    EXPECT_EQ(tune::cached_trials(off.trials), 0) << label;
    // Every file of the run but trials.csv: gains, history, comparison, front, ...
    std::map<std::string, std::string> files[2] = {tune::output_files(off),
                                                   tune::output_files(on)};
    EXPECT_EQ(files[1].count("front.json"), tune::front_objectives(job) >= 2 ? 1u : 0u) << label;
    files[0].erase("trials.csv");
    files[1].erase("trials.csv");
    EXPECT_EQ(files[1], files[0]) << label;
    EXPECT_EQ(states[1], states[0]) << label;
    EXPECT_LT(on.simulations, off.simulations) << label;
    EXPECT_EQ(on.trials.size(), off.trials.size()) << label;
    for (std::size_t i = 0; i < on.trials.size() && i < off.trials.size(); ++i) {
      const tune::Trial& a = on.trials[i];
      const tune::Trial& b = off.trials[i];
      EXPECT_EQ(a.parameters, b.parameters) << label << " " << i;
      if (a.capped || b.capped) continue;  // where capping stopped depends on the rounds' size
      EXPECT_EQ(std::bit_cast<std::uint64_t>(a.objective), std::bit_cast<std::uint64_t>(b.objective))
          << label << " " << i;
      EXPECT_EQ(std::bit_cast<std::uint64_t>(a.fitness), std::bit_cast<std::uint64_t>(b.fitness))
          << label << " " << i;
      EXPECT_EQ(a.scenario_objectives, b.scenario_objectives) << label << " " << i;
      EXPECT_EQ(a.diverged, b.diverged) << label << " " << i;
      EXPECT_EQ(a.goals.size(), b.goals.size()) << label << " " << i;
      for (std::size_t k = 0; k < a.goals.size() && k < b.goals.size(); ++k)
        EXPECT_TRUE(std::bit_cast<std::uint64_t>(a.goals[k]) ==
                        std::bit_cast<std::uint64_t>(b.goals[k]) ||
                    (std::isnan(a.goals[k]) && std::isnan(b.goals[k])))
            << label << " " << i << " " << k;
      EXPECT_EQ(a.accepted, b.accepted) << label << " " << i;
    }
    // Each cached row is a copy of the first row with the same parameters (which the cache
    // indexes: never a capped one unless both are of one batch).
    for (std::size_t i = 0; i < on.trials.size(); ++i) {
      const tune::Trial& a = on.trials[i];
      if (!a.cached) continue;
      std::size_t first = 0;
      while (first < i && (on.trials[first].parameters != a.parameters ||
                           (on.trials[first].capped && on.trials[first].iteration != a.iteration)))
        ++first;
      EXPECT_LT(first, i) << label << ": a cached row without its source";
      if (first == i) continue;
      const tune::Trial& b = on.trials[first];
      EXPECT_FALSE(b.cached) << label << " " << i;
      EXPECT_FALSE(a.accepted) << label << " " << i;
      EXPECT_EQ(tune::trials_json(on.trials, i)[0].dump(),
                [&] {
                  tune::Trial c = b;  // what the copy must be: the source, renumbered, marked
                  c.iteration = a.iteration;
                  c.index = a.index;
                  c.accepted = false;
                  c.cached = true;
                  return tune::trials_json({c})[0].dump();
                }())
          << label << " " << i;
    }
    const std::string csv = tune::trials_csv(on);
    if (threads == 2) {
      EXPECT_EQ(csv, one_thread) << label << ": what the cache served depends on threads";
    }
    one_thread = csv;
  }
  return one_thread;
}

}  // namespace

// The cache (issue 43) with the Bat algorithm (whose bats pile up on the bounds of a narrow box)
// on an ensemble job with capping, on a job with goals, and on a job of a Pareto front: the same
// gains, history, comparison, front and optimiser states with the cache on and off; trials.csv
// marks the rows served (cached 1, simulated 0), and with capping a capped row may have stopped
// elsewhere (the rounds hold fewer candidates).
TEST(TuningRun, CacheChangesNoFileButTrialsCsv) {
  json ensemble = short_ensemble_job();
  ensemble["ensemble"]["count"] = 11;
  json goals = goal_ensemble_job(1000, 30, true);
  json front = front_job();
  for (json* j : {&ensemble, &goals, &front}) {
    (*j)["tuning"]["algorithm"] = {{"type", "bat"}, {"population", 6}, {"iterations", 4}};
    // A box narrow enough for the bats to fly out of it, onto its bounds and corners.
    (*j)["tuning"]["parameters"] = {{"Kp", {5, 6}}, {"Ki", {1, 1.5}}};
  }
  front["tuning"]["parameters"] = {{"Kp", {5, 6}},
                                   {"switching_gain", {{"bounds", {2, 3}}, {"scale", "log"}}}};
  const std::string csv = compare_cache(ensemble, "ensemble");
  EXPECT_NE(csv.find(",accepted,capped,simulated,cached\n"), std::string::npos) << csv;
  EXPECT_NE(csv.find(",0,0,1\n"), std::string::npos) << csv;  // a cached row
  compare_cache(goals, "goals");
  compare_cache(front, "front");
}

// A run stopped after an iteration with cached trials before it and resumed serves what the
// uninterrupted run served: the same trials.csv, cached rows included, and the same gains.
TEST(TuningRun, ResumedRunServesFromTheCacheAsTheUninterruptedRun) {
  json j = short_ensemble_job();
  j["tuning"]["algorithm"] = {{"type", "bat"}, {"population", 6}, {"iterations", 4}};
  j["tuning"]["parameters"] = {{"Kp", {5, 6}}, {"Ki", {1, 1.5}}};
  const tune::Job job = tune::parse_job(j, "x");
  const tune::TuningOutcome whole = tuned(job, 2);
  const json state = checkpoint_after(job, 2);
  std::size_t cached_before = 0;  // a cached row ends with true
  for (const json& row : state["trials"])
    cached_before += row.back().is_boolean() && row.back().get<bool>() ? 1 : 0;
  EXPECT_GT(cached_before, 0u) << "no cached trial before the checkpoint: the test proves less";
  // A row after the checkpoint served from one before it: the resumed run must have rebuilt the
  // index from the checkpoint's trials.
  const std::size_t resumed_at = state["trials"].size();
  bool across = false;
  for (std::size_t i = resumed_at; i < whole.trials.size(); ++i)
    for (std::size_t k = 0; k < resumed_at && whole.trials[i].cached; ++k)
      across = across || whole.trials[k].parameters == whole.trials[i].parameters;
  EXPECT_TRUE(across) << "no trial after the checkpoint repeats one before it: the test proves less";
  expect_resumed_run_writes_the_same(job, state, whole);
}

// `ftctune run --no-cache` simulates a candidate each time it is proposed: the same gains.json
// and history.csv as the default, no cached row in its trials.csv, more simulations in run.json
// and "cached_trials" 0.
TEST(Cli, RunWithoutCacheWritesTheSameGainsAndNoCachedTrial) {
  const auto dir = fresh_dir("run-no-cache");
  json j = short_ensemble_job();
  j["tuning"]["algorithm"] = {{"type", "bat"}, {"population", 6}, {"iterations", 4}};
  j["tuning"]["parameters"] = {{"Kp", {5, 6}}, {"Ki", {1, 1.5}}};
  const CliResult a = run_with_and_without_flag(dir, j, "--no-cache");
  ASSERT_EQ(a.exit_code, 0);
  const json on = json::parse(slurp(dir / "on" / "run.json"));
  const json off = json::parse(slurp(dir / "off" / "run.json"));
  EXPECT_GT(on["cached_trials"].get<std::int64_t>(), 0);
  EXPECT_EQ(off["cached_trials"].get<std::int64_t>(), 0);
  EXPECT_GT(off["simulations"].get<std::int64_t>(), on["simulations"].get<std::int64_t>());
  // The summary says how many candidates the cache served.
  const std::int64_t served = on["cached_trials"].get<std::int64_t>();
  EXPECT_NE(a.out.find(std::to_string(served) +
                       (served == 1 ? " candidate proposed again took its earlier results"
                                    : " candidates proposed again took their earlier results")),
            std::string::npos)
      << a.out;
  // The rows whose cached column is 1.
  const auto cached_rows = [](const std::string& csv) {
    std::istringstream in(csv);
    std::string line;
    std::getline(in, line);
    std::vector<std::string> header;
    for (std::stringstream cs(line); std::getline(cs, line, ',');) header.push_back(line);
    const auto column = std::find(header.begin(), header.end(), "cached") - header.begin();
    int n = 0;
    while (std::getline(in, line)) {
      std::vector<std::string> cells;
      for (std::stringstream cs(line); std::getline(cs, line, ',');) cells.push_back(line);
      n += column < static_cast<std::ptrdiff_t>(cells.size()) && cells[column] == "1" ? 1 : 0;
    }
    return n;
  };
  EXPECT_EQ(cached_rows(slurp(dir / "on" / "trials.csv")), on["cached_trials"].get<int>());
  EXPECT_EQ(cached_rows(slurp(dir / "off" / "trials.csv")), 0);
}

// A checkpoint's trials keep a goal of +inf (a diverged member's) apart from NaN (no scenario
// defines the metric, or a capped row's goal without a bound), so that a resumed run's
// trials.csv shows each as the uninterrupted run did.
TEST(TuningRun, CheckpointTrialsKeepAnInfiniteGoalApartFromNaN) {
  tune::Trial t;
  t.iteration = 1;
  t.index = 0;
  t.parameters = {2.0};
  t.objective = std::numeric_limits<double>::infinity();
  t.fitness = 0.0;
  t.diverged = 1;
  t.scenario_objectives = {std::numeric_limits<double>::infinity()};
  t.goals = {std::numeric_limits<double>::infinity(), std::numeric_limits<double>::quiet_NaN(),
             0.25};
  t.violation = 0.5;
  t.capped = true;
  t.simulated = 3;
  const json rows = tune::trials_json({t});
  EXPECT_EQ(rows[0][8], json::array({"inf", nullptr, 0.25}));
  const std::vector<tune::Trial> back = tune::trials_from_json(json::parse(rows.dump()), 3);
  ASSERT_EQ(back.size(), 1u);
  ASSERT_EQ(back[0].goals.size(), 3u);
  EXPECT_TRUE(std::isinf(back[0].goals[0]) && back[0].goals[0] > 0);
  EXPECT_TRUE(std::isnan(back[0].goals[1]));
  EXPECT_EQ(back[0].goals[2], 0.25);
  EXPECT_TRUE(back[0].capped);
  EXPECT_EQ(back[0].simulated, 3u);
  EXPECT_THROW(tune::trials_from_json(json::array({json::array(
                                          {1, 0, json::array({2.0}), nullptr, 0.0, 1,
                                           json::array(), false, json::array({"-inf", nullptr, 0.25}),
                                           0.5})}),
                                      3),
               InputError);
}

// The summary gives the job's own controller's objective against the tuned one relative to the
// tuned objective, as the noise-floor sentence does, and as a ratio from a factor of two on:
// a 9 020-fold reduction read "100 % lower".
TEST(TuningRun, SummaryGivesAManyfoldChangeAsARatio) {
  const auto summary = [](double tuned, double own) {
    const json gains = {{"tuned", {{"Kp", 1.0}}},
                        {"controller", {{"type", "pi_fosmc"}, {"Kp", 1.0}}},
                        {"objective", {{"value", tuned}, {"metric", "ise"}}},
                        {"baseline", {{"objective", own}}},
                        {"fitness", 1 / tuned}};
    return tune::run_summary(gains, json::object(), {{"threads", 1}});
  };
  EXPECT_NE(summary(1e-3, 9.02).find("(job's own controller: 9.020000e+00, 9.02e+03 times the "
                                     "tuned)"),
            std::string::npos)
      << summary(1e-3, 9.02);
  EXPECT_NE(summary(1.0, 1.228).find(", 22.8 % above the tuned)"), std::string::npos)
      << summary(1.0, 1.228);
  EXPECT_NE(summary(1.0, 0.75).find(", 25 % below the tuned)"), std::string::npos)
      << summary(1.0, 0.75);
  EXPECT_NE(summary(1.0, 0.25).find(", 0.25 times the tuned)"), std::string::npos)
      << summary(1.0, 0.25);
  EXPECT_NE(summary(1.0, 1.0).find(", 0 % above the tuned)"), std::string::npos)
      << summary(1.0, 1.0);
}

// A tuned objective that beats the job's own only inside the noise floor is no improvement:
// the run says so (#41 item 1), and `run --strict` exits 4 on any warning, files written.
TEST(TuningRun, WarnsWhenTheTunedGainsWinOnlyInsideTheNoiseFloor) {
  tune::TuningOutcome r = tuned(short_job(), 2);
  ASSERT_EQ(r.comparison.size(), 4u);  // NFTSMC, FOSMC, the job's, the tuned
  for (tune::ComparedController& c : r.comparison) {
    c.outcome.evaluation.objective = 2.0;
    c.outcome.evaluation.scenarios.at(0).control_tv = 100;
  }
  r.comparison[3].outcome.evaluation.objective = 1.0;
  r.noise_floor->relative_spread = 0.01;
  r.comparison[2].outcome.evaluation.objective = 1.02;  // 2 % apart: beyond a floor of 1 %
  EXPECT_TRUE(tune::comparison_warnings(r).empty());
  r.comparison[2].outcome.evaluation.objective = 1.005;  // 0.5 %: inside it
  const std::vector<std::string> w = tune::comparison_warnings(r);
  ASSERT_EQ(w.size(), 1u);
  EXPECT_EQ(w[0],
            "The tuned gains beat the job's own on ISE[0 s, 5 s] only inside the noise floor: 1 "
            "against 1.005, 0.5 % apart, where nudging the initial state moves the tuned "
            "objective by up to 1 %; this is no improvement to claim, so keep the job's gains or "
            "widen the search.");

  const auto dir = fresh_dir("run-strict");
  const CliResult strict =
      run_cli("run --strict -q jobs/table1.json --out '" + (dir / "t").string() + "'", dir);
  EXPECT_EQ(strict.exit_code, 4) << strict.err;
  EXPECT_NE(strict.err.find("ftctune: error: --strict: the run gave 2 warnings"),
            std::string::npos)
      << strict.err;
  EXPECT_TRUE(std::filesystem::exists(dir / "t" / "gains.json"));
}
