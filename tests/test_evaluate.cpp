// Out-of-sample evaluation (`ftctune evaluate`): the numbers are those of simulating each member
// alone, the held-out members are those of the seed asked for, gains for another plant or
// sample time are refused, and the files it writes replay.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>

#include "cli_runner.hpp"
#include "ftc/sim/input_error.hpp"
#include "ftc/tune/evaluators/tbb_evaluator.hpp"
#include "ftc/tune/io/files.hpp"
#include "ftc/tune/job/ensemble.hpp"
#include "ftc/tune/problem/problem.hpp"
#include "ftc/tune/run/documents.hpp"
#include "ftc/tune/run/evaluate.hpp"
#include "ftc/tune/run/fault_fields.hpp"
#include "ftc/tune/run/tuning_run.hpp"
#include "short_job.hpp"

using nlohmann::json;
using namespace ftc;
using namespace ftc::testing;

namespace {

tune::Job ensemble_job() { return tune::parse_job(short_ensemble_job(), "robust-short"); }

// Two gains files for the spacecraft at Ts = 1 ms: a short tuning run's, and the same with
// other Kp and Ki (a second, different controller).
struct GainsFiles {
  std::filesystem::path a, b;
  json document;
};
const GainsFiles& gains_files() {
  static const GainsFiles files = [] {
    GainsFiles f;
    const std::filesystem::path dir = fresh_dir("evaluate-gains");
    tune::SerialEvaluator serial;
    const tune::TuningOutcome r = tune::tune(tune::parse_job(short_table1_job(), "short"), serial);
    f.document = tune::gains_document(r);
    f.a = dir / "a.json";
    tune::write_file_atomic(f.a, f.document.dump(2));
    json other = f.document;
    other["controller"]["Kp"] = 35.0;
    other["controller"]["Ki"] = 2.5;
    other["tuned"] = {{"Kp", 35.0}, {"Ki", 2.5}};
    f.b = dir / "b.json";
    tune::write_file_atomic(f.b, other.dump(2));
    return f;
  }();
  return files;
}

std::string refusal(const json& gains) {
  const std::filesystem::path file = fresh_dir("evaluate-refusal") / "gains.json";
  tune::write_file_atomic(file, gains.dump());
  tune::EvaluateOptions o;
  o.gains = {{file, ""}};
  tune::SerialEvaluator serial;
  try {
    tune::evaluate_out_of_sample(ensemble_job(), o, serial);
  } catch (const InputError& e) {
    return to_string(e.errors().at(0));
  }
  return "";
}

}  // namespace

TEST(Evaluate, GivesTheNumbersOfSimulatingEachMemberAlone) {
  const tune::Job job = ensemble_job();
  tune::EvaluateOptions o;
  o.gains = {{gains_files().a, "a"}, {gains_files().b, "b"}};
  tune::TbbEvaluator evaluator(2);
  const tune::EvaluationResult r = tune::evaluate_out_of_sample(job, o, evaluator);
  ASSERT_EQ(r.controllers.size(), 3u);  // the job's own (its compare list is empty), a, b
  EXPECT_EQ(r.controllers[0].label, "PI-FOSMC (job)");
  EXPECT_EQ(r.controllers[0].source, "job");
  EXPECT_EQ(r.controllers[1].label, "a");
  EXPECT_EQ(r.controllers[2].source, gains_files().b.string());
  EXPECT_EQ(r.seed, 8u);  // held out: the ensemble's seed 7 + 1
  EXPECT_EQ(r.count, 6);
  for (const tune::EvaluatedController& c : r.controllers) {
    ASSERT_EQ(c.members.size(), 7u) << c.label;  // the listed scenario and 6 members
    std::vector<double> counted;
    for (std::size_t i = 0; i < c.members.size(); ++i) {
      // The member on its own: a job with that one scenario and no ensemble.
      tune::Job one = job;
      one.ensemble = nullptr;
      one.scenarios = {i == 0 ? job.scenarios[0]
                              : tune::ensemble_member(job, 8, static_cast<std::int64_t>(i - 1))};
      const tune::TuningProblem alone(one);
      const sim::SimulationResult s = alone.simulate(c.controller, 0);
      EXPECT_EQ(c.members[i].scenario, one.scenarios[0].name);
      EXPECT_EQ(c.members[i].objective, s.metrics.errors.ise) << c.label << " " << i;
      EXPECT_EQ(c.members[i].metrics.get("iae"), s.metrics.errors.iae);
      EXPECT_EQ(c.members[i].metrics.get("control_tv"), s.metrics.control_tv);
      // Every field of the record, to the bit (NaN for a fault onset never reached).
      const std::vector<double> want = sim::MetricValues::of(s.metrics).values;
      ASSERT_EQ(c.members[i].metrics.values.size(), want.size());
      EXPECT_EQ(std::memcmp(c.members[i].metrics.values.data(), want.data(),
                            want.size() * sizeof(double)),
                0);
      EXPECT_EQ(c.members[i].recoverable, alone.recoverable(0));
      if (c.members[i].recoverable) counted.push_back(c.members[i].objective);
    }
    // CVaR at the job's alpha 0.9: the mean of the ceil(0.1 n) largest.
    std::sort(counted.begin(), counted.end());
    EXPECT_EQ(c.aggregates.cvar, counted.back()) << c.label;  // n ≤ 10: the largest alone
    EXPECT_EQ(c.aggregates.objective, c.aggregates.cvar);
    EXPECT_EQ(c.aggregates.max, counted.back());
    EXPECT_EQ(c.aggregates.counted, static_cast<int>(counted.size()));
  }
  // The two gains files are different controllers and score differently.
  EXPECT_NE(r.controllers[1].members[1].objective, r.controllers[2].members[1].objective);
}

TEST(Evaluate, SeedAndCountChooseTheHeldOutMembers) {
  tune::EvaluateOptions o;
  o.seed = 123;
  o.count = 3;
  tune::SerialEvaluator serial;
  const tune::EvaluationResult r = tune::evaluate_out_of_sample(ensemble_job(), o, serial);
  EXPECT_EQ(r.seed, 123u);
  ASSERT_EQ(r.controllers.front().members.size(), 4u);
  EXPECT_EQ(r.controllers.front().members[3].scenario, "paper-2");
  // Without an ensemble there is nothing to draw.
  tune::Job plain = ensemble_job();
  plain.ensemble = nullptr;
  try {
    tune::evaluate_out_of_sample(plain, o, serial);
    FAIL() << "a seed for a job without ensemble was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(to_string(e.errors().at(0)).find("has no ensemble"), std::string::npos);
  }
  o.seed.reset();
  o.count = 0;
  EXPECT_THROW(tune::evaluate_out_of_sample(ensemble_job(), o, serial), InputError);
}

TEST(Evaluate, RefusesGainsTunedForAnotherPlantOrSampleTime) {
  json g = gains_files().document;
  g["plant"]["inertia"] = {21, 17, 15};
  EXPECT_NE(refusal(g).find("/plant: was tuned for other plant values"), std::string::npos)
      << refusal(g);
  g = gains_files().document;
  g["sample_time"] = 0.002;
  EXPECT_NE(refusal(g).find("/sample_time: was tuned for Ts = 0.002 s; scenario \"paper\""),
            std::string::npos)
      << refusal(g);
  g = gains_files().document;
  g["plant"] = {{"model", "manipulator"}};
  EXPECT_NE(refusal(g).find("/plant/model: was tuned for the plant \"manipulator\""),
            std::string::npos)
      << refusal(g);
}

TEST(Evaluate, CommandWritesItsFilesAndTheWorstMembersReplay) {
  const std::filesystem::path dir = fresh_dir("evaluate-cli");
  tune::write_file_atomic(dir / "job.json", short_ensemble_job().dump(2));
  const std::string out = (dir / "ev").string();
  const CliResult r = run_cli("evaluate '" + (dir / "job.json").string() + "' --gains 'tuned=" +
                                  gains_files().a.string() + "' --threads 1 --out '" + out + "'",
                              dir);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  // --threads reaches the evaluator (it said "on 2 threads" on a 2-core machine).
  EXPECT_NE(r.out.find(" simulations on 1 thread in "), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("held-out seed 8 (the job's seed + 1)"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("controller"), std::string::npos);
  EXPECT_NE(r.out.find("CVaR"), std::string::npos);
  EXPECT_NE(r.out.find("tuned"), std::string::npos);
  const json doc = json::parse(slurp(dir / "ev" / "evaluation.json"));
  EXPECT_EQ(doc["schema"], "ftctune.evaluation/1");
  EXPECT_EQ(doc["seed"], 8);
  EXPECT_EQ(doc["count"], 6);
  EXPECT_EQ(doc["metric"], "ise");
  EXPECT_EQ(doc["aggregate"], "cvar");  // the objective in the job's own form
  EXPECT_EQ(doc["alpha"], 0.9);
  EXPECT_EQ(doc["window"], json::parse("[0, 4]"));
  EXPECT_EQ(doc["window_from"], "first_fault");
  ASSERT_EQ(doc["controllers"].size(), 2u);
  EXPECT_EQ(doc["controllers"][1]["label"], "tuned");
  EXPECT_EQ(doc["controllers"][1]["source"], gains_files().a.string());
  EXPECT_EQ(doc["controllers"][1]["members"].size(), 7u);
  EXPECT_TRUE(std::filesystem::exists(dir / "ev" / "evaluation.png"));
  // The figure: units on the axes, the unrecoverable members it leaves out said in the title,
  // each controller in its type's style (the job's PI-FOSMC 2, the first gains file 1).
  const std::string gp = slurp(dir / "ev" / "evaluation.gp");
  EXPECT_NE(gp.find("ISE of a member [rad²·s] (log scale)"), std::string::npos) << gp;
  const int unrecoverable = doc["controllers"][0]["aggregates"]["unrecoverable"].get<int>();
  EXPECT_EQ(gp.find(std::to_string(unrecoverable) + " unrecoverable members left out") !=
                std::string::npos,
            unrecoverable > 0)
      << gp;
  EXPECT_NE(gp.find("$cdf0 using 1:2 with steps ls 2 "), std::string::npos) << gp;
  EXPECT_NE(gp.find("$cdf1 using 1:2 with steps ls 1 "), std::string::npos) << gp;
  // One CSV row per controller × scenario, with the faults in words and as fields (two faults
  // at most: the listed scenario's, and each member's one or two).
  std::istringstream csv(slurp(dir / "ev" / "evaluation.csv"));
  std::string line;
  std::getline(csv, line);
  EXPECT_EQ(line, "controller,scenario,faults" + tune::fault_columns_header(2) +
                      ",recoverable,objective,ise,iae,itae,max_abs_u,control_tv,"
                      "peak_error_after_fault,control_energy,peak_command,saturation_fraction,"
                      "settling_time,steady_state_error,diverged");
  int rows = 0;
  while (std::getline(csv, line)) ++rows;
  EXPECT_EQ(rows, 2 * 7);
  // The worst member of the tuned gains, replayed by `simulate`, scores what evaluate said.
  const std::filesystem::path worst = dir / "ev" / "worst" / "02-tuned";
  ASSERT_TRUE(std::filesystem::exists(worst));
  std::filesystem::path first;
  for (const auto& e : std::filesystem::directory_iterator(worst))
    if (e.path().filename().string().rfind("1-", 0) == 0) first = e.path();
  ASSERT_FALSE(first.empty());
  const CliResult s = run_cli(
      "simulate '" + first.string() + "' -q --out '" + (dir / "replay").string() + "'", dir);
  ASSERT_EQ(s.exit_code, 0) << s.err;
  const json m = json::parse(slurp(dir / "replay" / "metrics.json"));
  double worst_objective = 0;
  for (const json& member : doc["controllers"][1]["members"])
    if (member["recoverable"].get<bool>())
      worst_objective = std::max(worst_objective, member["objective"].get<double>());
  EXPECT_EQ(m["objective"].get<double>(), worst_objective);
}

TEST(Evaluate, CommandRefusesAnUnfitGainsFileWithExitTwo) {
  const std::filesystem::path dir = fresh_dir("evaluate-unfit");
  json g = gains_files().document;
  g["sample_time"] = 0.002;
  tune::write_file_atomic(dir / "g.json", g.dump());
  const CliResult r =
      run_cli("evaluate jobs/robust-faults.json --gains '" + (dir / "g.json").string() + "'", dir);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("was tuned for Ts = 0.002 s"), std::string::npos) << r.err;
  const CliResult bad = run_cli("evaluate jobs/robust-faults.json --gains '=x.json'", dir);
  EXPECT_EQ(bad.exit_code, 2);
  EXPECT_NE(bad.err.find("expected FILE or LABEL=FILE"), std::string::npos) << bad.err;
}

TEST(Evaluate, MembersAcrossSliceBoundariesAreTheMembersAlone) {
  // 256 scenarios a slice: with the listed one first, members 255 and 256 fall on either side.
  const tune::Job job = ensemble_job();
  tune::EvaluateOptions o;
  o.count = 300;
  tune::TbbEvaluator evaluator(2);
  const tune::EvaluationResult r = tune::evaluate_out_of_sample(job, o, evaluator);
  ASSERT_EQ(r.controllers[0].members.size(), 301u);
  for (const std::int64_t k : {0, 254, 255, 256, 299}) {
    tune::Job one = job;
    one.ensemble = nullptr;
    one.scenarios = {tune::ensemble_member(job, 8, k)};
    const sim::SimulationResult s = tune::TuningProblem(one).simulate(job.controller, 0);
    const tune::MemberResult& m = r.controllers[0].members[static_cast<std::size_t>(k + 1)];
    EXPECT_EQ(m.scenario, "paper-" + std::to_string(k));
    EXPECT_EQ(m.objective, s.metrics.errors.ise) << "member " << k;
  }
}

TEST(Evaluate, CountThatWouldRenameAListedScenarioIsRefused) {
  json j = short_ensemble_job();
  j["scenarios"][0]["name"] = "nominal";
  j["ensemble"]["base"] = "nominal";
  json other = j["scenarios"][0];
  other["name"] = "nominal-10";  // member 10 once there are more than 10 members
  j["scenarios"].push_back(other);
  const tune::Job job = tune::parse_job(j, "x");  // 6 members: no clash
  tune::EvaluateOptions o;
  o.count = 11;
  tune::SerialEvaluator serial;
  try {
    tune::evaluate_out_of_sample(job, o, serial);
    FAIL() << "a member named like a listed scenario was accepted";
  } catch (const InputError& e) {
    EXPECT_EQ(e.errors().at(0).path, "/scenarios/1/name");
    EXPECT_NE(e.errors().at(0).message.find("also the name of ensemble member 10"),
              std::string::npos);
  }
}

TEST(Evaluate, MembersCarryTheirFaultsAsFields) {
  const tune::Job job = ensemble_job();
  tune::TbbEvaluator evaluator(2);
  tune::EvaluateOptions o;
  o.seed = 21;
  o.count = 5;
  const tune::EvaluationResult r = tune::evaluate_out_of_sample(job, o, evaluator);
  const std::filesystem::path dir = fresh_dir("evaluate-fault-fields");
  tune::write_evaluation(r, dir);
  // The scenarios evaluated: the listed one, then the members of seed 21.
  std::vector<sim::Scenario> scenarios = job.scenarios;
  for (const sim::Scenario& m : tune::expand_ensemble(job, 21, 5)) scenarios.push_back(m);
  const json doc = json::parse(slurp(dir / "evaluation.json"));
  const std::size_t n = tune::max_faults(job);
  ASSERT_EQ(n, 2u);

  std::istringstream csv(slurp(dir / "evaluation.csv"));
  std::string line;
  std::getline(csv, line);
  const auto split = [](const std::string& text) {
    std::vector<std::string> cells;
    std::size_t i = 0;
    for (std::size_t j; (j = text.find(',', i)) != std::string::npos; i = j + 1)
      cells.push_back(text.substr(i, j - i));
    cells.push_back(text.substr(i));
    return cells;
  };
  const std::vector<std::string> header = split(line);
  const auto column = [&](const std::string& name) {
    const auto it = std::find(header.begin(), header.end(), name);
    EXPECT_NE(it, header.end()) << name;
    return static_cast<std::size_t>(it - header.begin());
  };
  std::set<std::string> kinds;
  for (std::size_t i = 0; i < scenarios.size(); ++i) {
    const json& member = doc["controllers"][0]["members"][i];
    EXPECT_EQ(member["scenario"], scenarios[i].name);
    const std::vector<sim::Fault>& faults = scenarios[i].faults;
    ASSERT_EQ(member["faults"].size(), faults.size()) << member.dump();
    std::getline(csv, line);
    // No quoted cells before the fault columns here (the faults in words have no comma).
    const std::vector<std::string> cells = split(line);
    ASSERT_EQ(cells.size(), header.size()) << line;
    for (std::size_t k = 0; k < n; ++k) {
      const std::string p = "fault" + std::to_string(k + 1) + "_";
      if (k >= faults.size()) {
        for (const char* f : {"actuator", "kind", "time", "fraction"})
          EXPECT_EQ(cells[column(p + f)], "") << line;
        continue;
      }
      const sim::Fault& f = faults[k];
      const json& j = member["faults"][k];
      EXPECT_EQ(j["actuator"], f.actuator);
      EXPECT_EQ(j["kind"], sim::to_string(f.type));
      EXPECT_EQ(j["profile"], sim::to_string(f.profile.type));
      EXPECT_EQ(j["time"].get<double>(), f.onset);
      EXPECT_EQ(j.contains("rate"), f.profile.type == sim::FaultProfileType::incipient);
      EXPECT_EQ(j.contains("fraction"), f.type == sim::FaultType::loss_of_effectiveness);
      EXPECT_EQ(j.contains("offset"), f.type == sim::FaultType::bias);
      EXPECT_EQ(j.contains("value"), f.type == sim::FaultType::stuck);
      if (f.type == sim::FaultType::loss_of_effectiveness) {
        EXPECT_EQ(j["fraction"].get<double>(), f.fraction);
        EXPECT_EQ(std::stod(cells[column(p + "fraction")]), f.fraction);
        EXPECT_EQ(cells[column(p + "offset")], "");
      }
      EXPECT_EQ(cells[column(p + "actuator")], std::to_string(f.actuator));
      EXPECT_EQ(cells[column(p + "kind")], sim::to_string(f.type));
      EXPECT_EQ(std::stod(cells[column(p + "time")]), f.onset);  // %.17g: the same double
      kinds.insert(j["kind"].get<std::string>());
    }
  }
  EXPECT_GE(kinds.size(), 2u);  // the check saw more than one kind of fault
}

// A job with goals: every goal's aggregate per controller over the counted members is the goal's
// aggregate of the members' own metrics, and evaluation.json, evaluation.csv and the printed
// table carry them with their violations and feasibility.
TEST(Evaluate, ReportsEveryGoalAggregatedPerController) {
  json j = short_ensemble_job();
  const json objective = j["objective"];
  j.erase("objective");
  json soft = {{"metric", "ise"}, {"minimize", true}};
  for (const char* k : {"window", "window_from", "aggregate", "alpha"})
    if (objective.contains(k)) soft[k] = objective[k];
  j["goals"] = json::array({soft,
                            {{"metric", "control_tv"}, {"aggregate", "max"}, {"at_most", 1e9}},
                            {{"metric", "peak_command"}, {"aggregate", "mean"}, {"at_most", 1.0}}});
  const tune::Job job = tune::parse_job(j, "robust-goals");
  tune::EvaluateOptions o;
  o.count = 4;
  tune::TbbEvaluator evaluator(2);
  const tune::EvaluationResult r = tune::evaluate_out_of_sample(job, o, evaluator);
  for (const tune::EvaluatedController& c : r.controllers) {
    ASSERT_EQ(c.goals.size(), 3u);
    double tv = 0, peak_sum = 0;
    int counted = 0;
    for (const tune::MemberResult& m : c.members) {
      ASSERT_EQ(m.goals.size(), 3u);
      EXPECT_EQ(m.goals[0], m.objective);  // the soft goal is the objective's measure
      EXPECT_EQ(m.goals[1], m.metrics.get("control_tv"));
      EXPECT_EQ(m.goals[2], m.metrics.get("max_abs_u"));  // no window: the whole run's peak
      if (!m.recoverable) continue;
      ++counted;
      tv = std::max(tv, m.metrics.get("control_tv"));
      peak_sum += m.metrics.get("max_abs_u");
    }
    ASSERT_GT(counted, 1);
    EXPECT_EQ(c.goals[0], c.aggregates.objective) << c.label;
    EXPECT_EQ(c.goals[1], tv) << c.label;
    EXPECT_NEAR(c.goals[2], peak_sum / counted, 1e-12 * peak_sum) << c.label;
    EXPECT_GT(c.goals[2], 1.0);
    EXPECT_DOUBLE_EQ(c.violation, c.goals[2] - 1.0);
  }
  std::string text;
  tune::write_evaluation_json(r, [&](std::string_view s) { text.append(s); });
  const json doc = json::parse(text);
  const json& g = doc["controllers"][0]["goals"];
  EXPECT_EQ(g["goals"][1]["value"].get<double>(), r.controllers[0].goals[1]);
  EXPECT_EQ(g["goals"][2]["violation"].get<double>(), r.controllers[0].goals[2] - 1.0);
  EXPECT_FALSE(g["feasible"].get<bool>());
  EXPECT_EQ(doc["controllers"][0]["members"][1]["goals"][1].get<double>(),
            r.controllers[0].members[1].goals[1]);
  std::string csv;
  tune::write_evaluation_csv(r, [&](std::string_view s) { csv.append(s); });
  const std::string header = csv.substr(0, csv.find('\n'));
  EXPECT_NE(header.find(",diverged,goal0_ise,goal1_control_tv,goal2_peak_command"),
            std::string::npos)
      << header;
  const std::string table = tune::evaluation_table(r);
  EXPECT_NE(table.find("goal2: mean of peak command[0 s, end] over 5 scenarios <= 1"),
            std::string::npos)
      << table;
  EXPECT_NE(table.find("feasible"), std::string::npos);
}
