// The Pareto front of a run (run/front.hpp): the hypervolume against a hand example, the front,
// knee and noise flags of hand-made trials, pick's rules, and end-to-end runs of a job with two
// soft goals (front.json, reproducibility across threads and a resume, pick's gains file).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <functional>
#include <nlohmann/json.hpp>
#include <optional>
#include <random>
#include <sys/stat.h>
#include <span>
#include <tuple>
#include <utility>

#include "cli_runner.hpp"
#include "ftc/runtime/gains.hpp"
#include "ftc/sim/input_error.hpp"
#include "ftc/sim/isa.hpp"
#include "ftc/tune/api/api.hpp"
#include "ftc/tune/io/files.hpp"
#include "ftc/tune/job/ensemble.hpp"
#include "ftc/tune/optimizers/hypervolume.hpp"
#include "ftc/tune/optimizers/pareto_bat.hpp"
#include "ftc/tune/run/documents.hpp"
#include "ftc/tune/run/front.hpp"
#include "ftc/tune/run/tuning_run.hpp"
#include "short_job.hpp"

using nlohmann::json;
using namespace ftc;
using namespace ftc::testing;

namespace {

// Hand-made trials of a job with goals (ise soft, control_tv soft, peak_command hard).
tune::Trial trial(int iteration, double ise, double tv, double violation = 0.0) {
  tune::Trial t;
  t.iteration = iteration;
  t.parameters = {ise, tv};
  t.goals = {ise, tv, 1.0};
  t.violation = violation;
  t.fitness = violation > 0 ? -0.5 : 1.0 / ise;
  return t;
}

// `ftctune run -q --no-checkpoint --threads 1 FLAGS` of job j (written to dir/job.json) into
// dir/OUT.
CliResult run_job(const std::filesystem::path& dir, const json& j, const std::string& flags,
                  const std::string& out) {
  tune::write_file_atomic(dir / "job.json", j.dump());
  return run_cli("run -q --no-checkpoint --threads 1 " + flags + " '" +
                     (dir / "job.json").string() + "' --out '" + (dir / out).string() + "'",
                 dir);
}

}  // namespace

TEST(Hypervolume, ThreePointsInTwoDimensionsAgainstAHandComputedArea) {
  // (1, 3), (2, 2), (3, 1) against (4, 4): the staircase 1·1 + 1·2 + 1·3 = 6.
  EXPECT_DOUBLE_EQ(tune::hypervolume({{1, 3}, {2, 2}, {3, 1}}, {4, 4}), 6.0);
  // A dominated point adds nothing; a point not strictly inside the reference box neither.
  EXPECT_DOUBLE_EQ(tune::hypervolume({{1, 3}, {2, 2}, {3, 1}, {3, 3}, {5, 0.5}, {4, 1}}, {4, 4}),
                   6.0);
  EXPECT_DOUBLE_EQ(tune::hypervolume({{1, 1, 1}}, {2, 3, 4}), 6.0);
  EXPECT_EQ(tune::hypervolume({}, {1, 1}), 0.0);
  EXPECT_THROW(tune::hypervolume({{1, 1, 1}}, {2, 2}), std::invalid_argument);
}

TEST(Front, OfHandMadeTrialsWithReferenceKneeAndHypervolumePerIteration) {
  const tune::Job job = tune::parse_job(front_job(), "front");
  // log10 of (ise, tv): (0, 3) (1, 1) (3, 0) on the front; (2, 2) dominated by (1, 1); an
  // infeasible (0.1, 0.1); a repeat of (10, 10) later.
  const std::vector<tune::Trial> trials = {trial(0, 1, 1000),       trial(0, 100, 100),
                                           trial(0, 0.1, 0.1, 0.5), trial(1, 10, 10),
                                           trial(1, 1000, 1),       trial(2, 10, 10)};
  EXPECT_EQ(tune::front_trials(job, trials, trials.size()), (std::vector<std::size_t>{0, 3, 4}));
  EXPECT_EQ(tune::front_trials(job, trials, 3), (std::vector<std::size_t>{0, 1}));
  const tune::Front f = tune::make_front(job, trials);
  ASSERT_EQ(f.points.size(), 3u);
  EXPECT_EQ(f.points[1].trial, 3u);
  ASSERT_EQ(f.reference.size(), 2u);
  EXPECT_DOUBLE_EQ(f.reference[0], 3.1);
  EXPECT_DOUBLE_EQ(f.reference[1], 3.1);
  // Staircase on log10 against (3.1, 3.1): 1·0.1 + 2·2.1 + 0.1·3.1 = 4.61.
  EXPECT_NEAR(f.hypervolume, 4.61, 1e-12);
  // Normalised: (0, 1), (1/3, 1/3), (1, 0); the line x + y = 1; (1/3, 1/3) is the knee.
  EXPECT_EQ(f.picked, 1u);
  const std::vector<double> hv = tune::hypervolume_history(job, trials, f.reference, 2);
  ASSERT_EQ(hv.size(), 3u);
  // Iteration 0: (0, 3) and (2, 2): 2·0.1 + 1.1·1.1 = 1.41.
  EXPECT_NEAR(hv[0], 1.41, 1e-12);
  EXPECT_NEAR(hv[1], f.hypervolume, 1e-12);
  EXPECT_EQ(hv[2], hv[1]);
}

TEST(Front, IncrementalHypervolumeHistoryIsTheFromScratchOne) {
  // A few hundred trials on a coarse grid (repeats and ties in one goal), some infeasible, over
  // 12 iterations: the front and the hypervolume after each iteration as the definition
  // computes them from scratch (every earlier trial, all pairs), to the bit.
  const tune::Job job = tune::parse_job(front_job(), "front");
  std::mt19937_64 rng(26);
  std::vector<tune::Trial> trials;
  for (int it = 0; it < 12; ++it)
    for (int k = 0; k < 25; ++k) {
      // A trade-off with scatter: the second goal falls as the first rises.
      const auto a = static_cast<double>(rng() % 40), b = 39 - a + static_cast<double>(rng() % 6);
      const double ise = std::pow(10.0, a / 10 - 2), tv = std::pow(10.0, b / 10 - 2);
      trials.push_back(trial(it, ise, tv, rng() % 7 == 0 ? 0.5 : 0.0));
    }
  const auto from_scratch = [&](std::size_t count) {
    std::vector<std::size_t> kept;
    for (std::size_t i = 0; i < count; ++i) {
      if (trials[i].violation > 0) continue;
      bool repeat = false;
      for (std::size_t j : kept)
        repeat = repeat || (trials[j].goals[0] == trials[i].goals[0] &&
                            trials[j].goals[1] == trials[i].goals[1]);
      if (!repeat) kept.push_back(i);
    }
    std::vector<std::size_t> front;
    for (std::size_t i : kept) {
      bool dominated = false;
      for (std::size_t j : kept) {
        const double *a = trials[j].goals.data(), *b = trials[i].goals.data();
        dominated = dominated || (a[0] <= b[0] && a[1] <= b[1] && (a[0] < b[0] || a[1] < b[1]));
      }
      if (!dominated) front.push_back(i);
    }
    std::sort(front.begin(), front.end(), [&](std::size_t a, std::size_t b) {
      return std::make_pair(trials[a].goals[0], trials[a].goals[1]) <
             std::make_pair(trials[b].goals[0], trials[b].goals[1]);
    });
    return front;
  };
  const tune::Front f = tune::make_front(job, trials);
  ASSERT_GE(f.points.size(), 3u);
  const std::vector<double> hv = tune::hypervolume_history(job, trials, f.reference, 11);
  ASSERT_EQ(hv.size(), 12u);
  for (int it = 0; it < 12; ++it) {
    const std::size_t count = static_cast<std::size_t>(25 * (it + 1));
    const std::vector<std::size_t> front = from_scratch(count);
    EXPECT_EQ(tune::front_trials(job, trials, count), front) << it;
    std::vector<std::vector<double>> p;
    for (std::size_t i : front) p.push_back(tune::log_soft_goals(trials[i].goals, {0, 1}));
    EXPECT_EQ(hv[static_cast<std::size_t>(it)], tune::hypervolume(p, f.reference)) << it;
  }
}

TEST(Front, PointsWithinTheNoiseFloorOfTheirNeighbourAreFlaggedByEachPointsOwnFloor) {
  const tune::Job job = tune::parse_job(front_job(), "front");
  const std::vector<tune::Trial> trials = {trial(0, 1, 100), trial(0, 1.001, 99.95),
                                           trial(0, 2, 50)};
  tune::Front f = tune::make_front(job, trials);
  ASSERT_EQ(f.points.size(), 3u);
  using Floors = std::vector<std::vector<std::optional<double>>>;
  const std::optional<double> none;
  const auto with = [&](std::optional<double> a0, std::optional<double> a1,
                        std::optional<double> b0, std::optional<double> b1) {
    tune::apply_noise_floor(f, Floors{{a0, a1, none}, {b0, b1, none}, {0.002, 0.002, none}});
    return f.points[1].within_noise_of.has_value();
  };
  // (1, 100) and (1.001, 99.95) differ by 0.1 % and 0.05 %: within a floor of 0.2 % of either,
  // whichever point has it (each point's own floor, the larger counts), not within 0.01 %.
  EXPECT_TRUE(with(0.002, 0.002, 0.002, 0.002));
  EXPECT_EQ(*f.points[1].within_noise_of, 0u);
  EXPECT_FALSE(f.points[0].within_noise_of);
  EXPECT_FALSE(f.points[2].within_noise_of);  // (2, 50): far beyond 0.2 %
  EXPECT_TRUE(with(0.002, 0.002, 0.0001, 0.0001));
  EXPECT_TRUE(with(0.0001, 0.0001, 0.002, 0.002));
  EXPECT_FALSE(with(0.0001, 0.0001, 0.0001, 0.0001));
  // One goal inside only the first point's floor, the other only the second's: within.
  EXPECT_TRUE(with(0.002, 0.0001, 0.0001, 0.002));
  // Inside on the ISE, outside on the TV by both floors: a trade-off.
  EXPECT_FALSE(with(0.002, 0.0001, 0.002, 0.0001));
  // A floor measured at one point only counts; measured at neither, the points are told apart.
  EXPECT_TRUE(with(0.002, 0.002, none, none));
  EXPECT_TRUE(with(none, none, 0.002, 0.002));
  EXPECT_FALSE(with(0.002, none, 0.002, none));
  // Each point keeps its own floor.
  with(0.002, 0.003, 0.004, 0.005);
  EXPECT_EQ(*f.points[0].noise_floor[1], 0.003);
  EXPECT_EQ(*f.points[1].noise_floor[0], 0.004);
  EXPECT_FALSE(f.points[1].noise_floor[2]);
  const json doc = tune::front_document(job, "sha", 1, f);
  EXPECT_EQ(doc["points"][1]["noise_floor"][1], 0.005);
  EXPECT_TRUE(doc["points"][1]["noise_floor"][2].is_null());
  EXPECT_EQ(doc["points"][1]["within_noise_of"], 0u);
  EXPECT_FALSE(doc["points"][2].contains("within_noise_of"));
  // Each point lists its partners, both ways; a point without one an empty list.
  EXPECT_EQ(doc["points"][0]["within_noise"], json::array({1}));
  EXPECT_EQ(doc["points"][1]["within_noise"], json::array({0}));
  EXPECT_EQ(doc["points"][2]["within_noise"], json::array());
  EXPECT_NE(tune::front_csv(job, f).find(",0.0040000000000000001,0.0050000000000000001,,"),
            std::string::npos)
      << tune::front_csv(job, f);
}

TEST(Front, ARunOfPointsEachWithinItsNeighboursFloorIsNamedByItsFirst) {
  const tune::Job job = tune::parse_job(front_job(), "front");
  const std::vector<tune::Trial> trials = {trial(0, 1, 100), trial(0, 1.0015, 99.85),
                                           trial(0, 1.003, 99.7), trial(0, 2, 50)};
  tune::Front f = tune::make_front(job, trials);
  ASSERT_EQ(f.points.size(), 4u);
  const std::vector<std::optional<double>> floor = {0.002, 0.002, std::nullopt};
  tune::apply_noise_floor(f, {floor, floor, floor, floor});
  // #2 differs from #0 by 0.3 % (beyond its floor) but from #1 by 0.15 %: the chain #0-#1-#2.
  EXPECT_FALSE(tune::within_noise_floor(f, 0, 2));
  ASSERT_TRUE(f.points[1].within_noise_of && f.points[2].within_noise_of);
  EXPECT_EQ(*f.points[1].within_noise_of, 0u);
  EXPECT_EQ(*f.points[2].within_noise_of, 0u);
  EXPECT_FALSE(f.points[3].within_noise_of);
  // The partners: #2 is no trade-off with #0 too (its within_noise_of names it), though the two
  // are not within each other's floor; #3 with none.
  EXPECT_TRUE(tune::no_trade_off(f, 0, 2));
  EXPECT_TRUE(tune::no_trade_off(f, 2, 0));
  EXPECT_FALSE(tune::no_trade_off(f, 2, 3));
  EXPECT_EQ(f.points[0].within_noise, (std::vector<std::size_t>{1, 2}));
  EXPECT_EQ(f.points[1].within_noise, (std::vector<std::size_t>{0, 2}));
  EXPECT_EQ(f.points[2].within_noise, (std::vector<std::size_t>{0, 1}));
  EXPECT_TRUE(f.points[3].within_noise.empty());
}

// front.json carries each goal's words (the metric's label, window, aggregate) and unit, each
// point's partners and the compared controllers; front_from_json reads back the Front the run
// wrote, field for field.
TEST(Front, DocumentCarriesLabelsPartnersAndComparedAndReadsBackAsWritten) {
  json j = front_job();
  // An aggregate over several scenarios enters the label.
  j["scenarios"].push_back(j["scenarios"][0]);
  j["scenarios"][1]["name"] = "again";
  j["goals"][1]["aggregate"] = "quantile";
  j["goals"][1]["q"] = 0.5;
  const tune::Job job = tune::parse_job(j, "front");
  tune::Front f =
      tune::make_front(job, {trial(0, 1, 100), trial(0, 1.001, 99.95), trial(0, 2, 50)});
  const std::optional<double> none;
  tune::apply_noise_floor(f, {{0.002, 0.002, none}, {0.002, 0.002, none}, {none, none, none}});
  f.compared.push_back({"Table 1", "compare", {3, 40, 2}, true});
  f.compared.push_back({"PI-FOSMC (job)", "baseline", {INFINITY, 5, 9}, false});
  const json doc = tune::front_document(job, "sha", 1, f);
  const json& goals = doc["goals"];
  EXPECT_EQ(goals[0]["label"], "mean of ISE[0 s, 5 s] over 2 scenarios");
  EXPECT_EQ(goals[0]["unit"], "rad²·s");
  EXPECT_EQ(goals[1]["label"], "quantile0.5 of control TV over 2 scenarios");  // no window
  EXPECT_EQ(goals[1]["unit"], "command's unit");
  EXPECT_EQ(goals[2]["label"], "mean of peak command[0 s, end] over 2 scenarios");
  EXPECT_EQ(goals[2]["metric"], "peak_command");       // the goal's own form beside them
  EXPECT_EQ(doc["compared"][1]["goals"][0], nullptr);  // a diverged value
  EXPECT_EQ(doc["compared"][1]["role"], "baseline");

  const tune::Front back = tune::front_from_json(job, json::parse(doc.dump()));
  ASSERT_EQ(back.goals.size(), 3u);
  for (std::size_t k = 0; k < 3; ++k) {
    EXPECT_EQ(back.goals[k].label, f.goals[k].label);
    EXPECT_EQ(back.goals[k].unit, f.goals[k].unit);
    EXPECT_EQ(back.goals[k].at_most, job.goals[k].at_most);
  }
  EXPECT_EQ(back.soft, f.soft);
  ASSERT_EQ(back.points.size(), f.points.size());
  for (std::size_t i = 0; i < f.points.size(); ++i) {
    EXPECT_EQ(back.points[i].parameters, f.points[i].parameters);
    EXPECT_EQ(back.points[i].goals, f.points[i].goals);
    EXPECT_EQ(back.points[i].noise_floor, f.points[i].noise_floor);
    EXPECT_EQ(back.points[i].within_noise_of, f.points[i].within_noise_of);
    EXPECT_EQ(back.points[i].within_noise, f.points[i].within_noise);
    EXPECT_EQ(back.points[i].trial, f.points[i].trial);
  }
  EXPECT_EQ(back.reference, f.reference);
  EXPECT_EQ(back.hypervolume, f.hypervolume);
  EXPECT_EQ(back.picked, f.picked);
  ASSERT_EQ(back.compared.size(), 2u);
  EXPECT_EQ(back.compared[1].label, "PI-FOSMC (job)");
  EXPECT_EQ(back.compared[1].goals, (std::vector<double>{INFINITY, 5, 9}));
  EXPECT_FALSE(back.compared[1].feasible);

  // Written before the labels and partners (the same schema name): read with the job's words
  // and the rule's partners, as the run writes them now.
  json old = json::parse(doc.dump());
  for (json& g : old["goals"]) {
    g.erase("label");
    g.erase("unit");
  }
  for (json& p : old["points"]) p.erase("within_noise");
  const tune::Front filled = tune::front_from_json(job, old);
  for (std::size_t k = 0; k < 3; ++k) EXPECT_EQ(filled.goals[k].label, f.goals[k].label);
  for (std::size_t i = 0; i < f.points.size(); ++i)
    EXPECT_EQ(filled.points[i].within_noise, f.points[i].within_noise) << i;
}

// A damaged front.json is refused at the JSON path of what is wrong with it.
TEST(Front, ADamagedDocumentIsRefusedAtItsPath) {
  const tune::Job job = tune::parse_job(front_job(), "front");
  tune::Front f = tune::make_front(job, {trial(0, 1, 100), trial(0, 2, 50)});
  tune::apply_noise_floor(f, {{0.002, 0.002, std::nullopt}, {0.002, 0.002, std::nullopt}});
  const json doc = tune::front_document(job, "sha", 1, f);
  const auto refused_at = [&](const std::function<void(json&)>& damage, const std::string& path) {
    json j = doc;
    damage(j);
    try {
      tune::front_from_json(job, j, "run/front.json");
      ADD_FAILURE() << "accepted, expected a refusal at " << path;
    } catch (const InputError& e) {
      EXPECT_EQ(e.source(), "run/front.json");
      ASSERT_FALSE(e.errors().empty());
      EXPECT_EQ(e.errors()[0].path, path) << e.what();
    }
  };
  refused_at([](json& j) { j["schema"] = "ftctune.front/0"; }, "/schema");
  refused_at([](json& j) { j["goals"].erase(2); }, "/goals");
  refused_at([](json& j) { j["goals"][1]["metric"] = "iae"; }, "/goals/1/metric");
  refused_at([](json& j) { j["goals"][0]["label"] = 3; }, "/goals/0/label");
  refused_at([](json& j) { j["points"][1]["goals"].erase(2); }, "/points/1/goals");
  refused_at([](json& j) { j["points"][0]["parameters"].erase("Kp"); }, "/points/0/parameters/Kp");
  refused_at([](json& j) { j["points"][0]["noise_floor"][1] = "x"; }, "/points/0/noise_floor/1");
  refused_at([](json& j) { j["points"][1]["within_noise_of"] = 1; }, "/points/1/within_noise_of");
  refused_at([](json& j) { j["points"][1]["within_noise"] = {0, 7}; }, "/points/1/within_noise/1");
  refused_at([](json& j) { j["points"][0]["trial"] = -1; }, "/points/0/trial");
  refused_at([](json& j) { j["reference_point"].erase(1); }, "/reference_point");
  refused_at([](json& j) { j["reference_point"][1] = "far"; }, "/reference_point/1");
  refused_at([](json& j) { j["picked"]["index"] = 2; }, "/picked/index");
  refused_at(
      [](json& j) {
        j["compared"] = {{{"label", "x"}, {"goals", {1, 2}}}};
      },
      "/compared/0/goals");
  // A job of one soft goal has no front to read.
  json one_soft = front_job();
  one_soft["goals"][1] = {{"metric", "control_tv"}, {"at_most", 1e9}};
  try {
    tune::front_from_json(tune::parse_job(one_soft, "one soft goal"), doc);
    ADD_FAILURE() << "a front of a job with one soft goal was read";
  } catch (const InputError& e) {
    EXPECT_EQ(e.errors().at(0).path, "/goals");
  }
}

// front.json carries authority (pick's output is deployable): a front of another job, gains of
// another job, a point outside the bounds, infeasible, or not the trial trials.csv recorded, and
// files that are not regular files are each refused at their path, never turned into gains.
TEST(Front, PickChecksEveryPointAgainstTheRunsOwnFiles) {
  const tune::Job job = tune::parse_job(front_job(), "front");
  const auto files = tune::output_files(tuned(job, 1));
  const json front = json::parse(files.at("front.json"));
  const json gains = json::parse(files.at("gains.json"));
  ASSERT_GE(front["points"].size(), 2u);
  const auto forged = [&](const std::function<void(json&)>& change) {
    json f = front;
    change(f);
    return f;
  };
  json other_gains = gains;
  other_gains["job"]["sha256"] = std::string(64, 'a');
  const double kp1 = front["points"][1]["parameters"]["Kp"].get<double>();
  const double ise0 = front["points"][0]["goals"][0].get<double>();
  // file, text, path of the error, words it must hold
  const std::vector<std::tuple<std::string, std::string, std::string, std::string>> cases = {
      {"front.json", forged([](json& f) { f["job_sha256"] = std::string(64, 'b'); }).dump(),
       "/job_sha256", "a front of another job"},
      {"front.json", forged([](json& f) { f.erase("job_sha256"); }).dump(), "/job_sha256",
       "is missing: it must be the sha256"},
      {"gains.json", other_gains.dump(), "/job/sha256", "gains of another job"},
      {"front.json", forged([](json& f) { f["points"][0]["parameters"]["Kp"] = 1e300; }).dump(),
       "/points/0/parameters/Kp", "outside the job's bounds [1, 50]"},
      {"front.json",
       forged([&](json& f) { f["points"][0]["parameters"]["Kp"] = kp1; }).dump(),
       "/points/0/parameters/Kp", ", but trial "},
      {"front.json",
       forged([&](json& f) { f["points"][0]["goals"][0] = std::nextafter(ise0, 1.0); }).dump(),
       "/points/0/goals/0", "trials.csv has"},
      {"front.json", forged([](json& f) { f["points"][0]["violation"] = 5; }).dump(),
       "/points/0/violation", "meets every hard goal"},
      {"front.json", forged([](json& f) { f["points"][0]["goals"][2] = 2e6; }).dump(),
       "/points/0/goals/2", "meets every hard goal"},
      {"front.json", "{\"schema\": \"ftctune.front/1\", \"schema\": 1}", "/schema",
       "duplicate key"},
  };
  for (const auto& [file, text, path, words] : cases) {
    const auto dir = fresh_dir("pick-forged");
    tune::write_output_files(files, dir);
    tune::write_file_atomic(dir / file, text);
    try {
      tune::pick_gains(dir, "index:0");
      ADD_FAILURE() << path << " was not refused";
    } catch (const InputError& e) {
      EXPECT_EQ(e.source(), (dir / file).string()) << path;
      ASSERT_FALSE(e.errors().empty()) << path;
      EXPECT_EQ(e.errors().at(0).path, path) << e.what();
      EXPECT_NE(std::string(e.what()).find(words), std::string::npos) << e.what();
    }
    const CliResult refused = run_cli("pick '" + dir.string() + "' --rule index:0", dir);
    EXPECT_EQ(refused.exit_code, 2) << path << ": " << refused.err;
  }
  // Not regular files: a directory and a FIFO (which is not waited for) in front.json's place.
  for (const bool fifo : {false, true}) {
    const auto dir = fresh_dir("pick-not-a-file");
    tune::write_output_files(files, dir);
    std::filesystem::remove(dir / "front.json");
    if (fifo)
      ASSERT_EQ(::mkfifo((dir / "front.json").c_str(), 0600), 0);
    else
      std::filesystem::create_directory(dir / "front.json");
    const CliResult r = run_cli("pick '" + dir.string() + "' --rule index:0", dir);
    EXPECT_EQ(r.exit_code, 2) << r.err;
    EXPECT_NE(r.err.find("front.json"), std::string::npos) << r.err;
    EXPECT_EQ(r.err.find("internal error"), std::string::npos) << r.err;
  }
  // The untouched files still pick.
  const auto dir = fresh_dir("pick-whole");
  tune::write_output_files(files, dir);
  EXPECT_EQ(tune::pick_gains(dir, "knee"), gains);
}

// A point that a compared controller (the job's own gains, a compare entry) dominates on the soft
// goals is flagged, in front.json, front.csv, the run's summary and the gains pick writes: taking
// it gives up something for nothing (issue 41: point 18 of the shipped robust front was dominated
// by the job's own gains, listed in the same file, and nothing said so).
TEST(Front, PointsACompareControllerDominatesAreFlaggedAndPickWarnsOfThem) {
  const tune::Job job = tune::parse_job(front_job(), "front");
  tune::Front f = tune::make_front(job, {trial(0, 1, 100), trial(0, 2, 50), trial(0, 4, 20)});
  ASSERT_EQ(f.points.size(), 3u);
  f.compared = {{"NFTSMC", "compare", {2, 40, 1}, false},  // infeasible: dominates nothing
                {"PI-FOSMC (job)", "baseline", {1.5, 50, 1}, true},
                {"FOSMC", "compare", {2, 50, 1}, true}};  // equal to point 1: no better
  tune::mark_dominated_by_compared(f);
  EXPECT_FALSE(f.points[0].dominated_by);
  ASSERT_TRUE(f.points[1].dominated_by);
  EXPECT_EQ(*f.points[1].dominated_by, "PI-FOSMC (job)");
  EXPECT_FALSE(f.points[2].dominated_by);
  const json doc = tune::front_document(job, "sha", 1, f);
  EXPECT_EQ(doc["points"][1]["dominated_by"], "PI-FOSMC (job)");
  EXPECT_FALSE(doc["points"][0].contains("dominated_by"));
  const std::string csv = tune::front_csv(job, f);
  EXPECT_NE(csv.find(",trial,dominated_by\n"), std::string::npos) << csv;
  EXPECT_NE(csv.find(",PI-FOSMC (job)\n"), std::string::npos) << csv;
  EXPECT_EQ(tune::dominated_warning(f, 0), "");
  EXPECT_EQ(tune::dominated_warning(f, 1).rfind("front point 1 is dominated by PI-FOSMC (job) (", 0),
            0u)
      << tune::dominated_warning(f, 1);
  // Read back, the flag is derived again from the compared controllers, not taken from the file.
  json tampered = doc;
  tampered["points"][0]["dominated_by"] = "FOSMC";
  const tune::Front back = tune::front_from_json(job, tampered, "front.json");
  EXPECT_FALSE(back.points[0].dominated_by);
  EXPECT_EQ(back.points[1].dominated_by, f.points[1].dominated_by);

  // Through pick, on a real run whose front.json lists a controller that beats point 0's ISE at
  // its control TV.
  const auto files = tune::output_files(tuned(job, 1));
  json front = json::parse(files.at("front.json"));
  ASSERT_GE(front["points"].size(), 2u);
  ASSERT_FALSE(front["compared"].empty());
  json& better = front["compared"][0];
  better["feasible"] = true;
  better["goals"] = front["points"][0]["goals"];
  better["goals"][0] = 0.5 * front["points"][0]["goals"][0].get<double>();
  const std::string label = better["label"];
  const auto dir = fresh_dir("pick-dominated");
  tune::write_output_files(files, dir);
  tune::write_file_atomic(dir / "front.json", front.dump());
  const json g0 = tune::pick_gains(dir, "index:0");
  EXPECT_EQ(g0["goals"]["front"]["dominated_by"], label);
  std::size_t said = 0;
  for (const json& w : g0["warnings"])
    said += w.get<std::string>().rfind("front point 0 is dominated by " + label, 0) == 0 ? 1 : 0;
  EXPECT_EQ(said, 1u) << g0["warnings"].dump();
  const json g1 = tune::pick_gains(dir, "index:1");
  EXPECT_FALSE(g1["goals"]["front"].contains("dominated_by"));
  for (const json& w : g1["warnings"])
    EXPECT_EQ(w.get<std::string>().find(" is dominated by "), std::string::npos) << w;
  const CliResult r = run_cli(
      "pick '" + dir.string() + "' --rule index:0 --out '" + (dir / "g.json").string() + "'", dir);
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("[warning] front point 0 is dominated by " + label), std::string::npos)
      << r.err;
}

// The held-out front of a job without an ensemble is the run's own front: the same scenarios,
// the same simulations, so every point's held-out goals are its run values to the bit, and
// pick on it gives the run's gains (issue 42 item 1).
TEST(Front, HeldOutFrontOfAJobWithoutAnEnsembleIsTheRunsOwnToTheBit) {
  const tune::Job job = tune::parse_job(front_job(), "front");
  const auto dir = fresh_dir("held-out-same");
  tune::write_output_files(tune::output_files(tuned(job, 1)), dir / "run");
  tune::EvaluateJobOptions o;
  o.front = dir / "run";
  o.out = dir / "held";
  o.figure = false;
  o.threads = 1;
  const tune::EvaluateJobResult r = tune::evaluate_job(job, o);
  ASSERT_TRUE(r.front && r.front->held_out);
  const tune::Front& f = *r.front;
  EXPECT_EQ(f.held_out->seed, 0u);
  EXPECT_EQ(f.held_out->count, 0);
  ASSERT_GE(f.points.size(), 2u);
  for (const tune::FrontPoint& p : f.points) {
    EXPECT_EQ(p.goals, p.in_sample);
    EXPECT_FALSE(p.dominated);
  }
  EXPECT_EQ(f.hypervolume, f.held_out->in_sample_hypervolume);
  // Written whole, read back as written.
  const json doc = json::parse(slurp(dir / "held" / "front.json"));
  EXPECT_EQ(doc["held_out"]["run"], std::filesystem::weakly_canonical(dir / "run").string());
  EXPECT_EQ(tune::front_document(job, doc["job_sha256"], doc["seed"],
                                 tune::front_from_json(job, doc)),
            doc);
  // pick on it: the run's gains for the same point, with the held-out values beside them.
  json held = tune::pick_gains(dir / "held", "index:1");
  json own = tune::pick_gains(dir / "run", "index:1");
  EXPECT_EQ(held["goals"]["front"]["held_out"]["goals"], doc["points"][1]["goals"]);
  EXPECT_EQ(held["goals"]["front"]["held_out"]["warnings"], json::array());
  held["goals"]["front"].erase("held_out");
  own.erase("noise_floor");
  EXPECT_EQ(held, own);
}

// With an ensemble the held-out members differ: the points keep their run values in in_sample,
// the held-out front keeps the points its values do not dominate, pick picks on it and names
// each soft goal a point does not hold beyond its noise floor; the run's files stay the
// authority (a forged in_sample is refused); a front of another job is no --front.
TEST(Front, HeldOutFrontPicksOnHeldOutValuesAndSaysWhereAPointDoesNotHold) {
  json j = short_ensemble_job();
  j["name"] = "held-out-short";
  j.erase("objective");
  j["goals"] = {{{"metric", "ise"},
                 {"window", {0, 4}},
                 {"window_from", "first_fault"},
                 {"aggregate", "cvar"},
                 {"alpha", 0.9},
                 {"minimize", true}},
                {{"metric", "control_tv"}, {"minimize", true}}};
  j["tuning"]["parameters"] = {{"Kp", {1, 50}},
                               {"switching_gain", {{"bounds", {2, 200}}, {"scale", "log"}}}};
  j["tuning"]["algorithm"] = {{"type", "bat"}, {"population", 4}, {"iterations", 2}};
  const tune::Job job = tune::parse_job(j, "held-out");
  const auto dir = fresh_dir("held-out-ensemble");
  tune::write_output_files(tune::output_files(tuned(job, 2)), dir / "run");
  const json run_front = json::parse(slurp(dir / "run" / "front.json"));
  tune::write_file_atomic(dir / "job.json", j.dump());
  const CliResult cli = run_cli("evaluate '" + (dir / "job.json").string() + "' --front '" +
                                    (dir / "run").string() + "' --count 12 --no-figure --out '" +
                                    (dir / "held").string() + "'",
                                dir);
  ASSERT_EQ(cli.exit_code, 0) << cli.err;
  EXPECT_NE(cli.out.find("held-out front: "), std::string::npos) << cli.out;
  const json doc = json::parse(slurp(dir / "held" / "front.json"));
  EXPECT_EQ(doc["held_out"]["seed"], job.ensemble->seed + 1);
  EXPECT_EQ(doc["held_out"]["count"], 12);
  EXPECT_EQ(doc["held_out"]["in_sample_hypervolume"], run_front["hypervolume"]);
  ASSERT_EQ(doc["points"].size(), run_front["points"].size());
  EXPECT_NE(doc["goals"][0]["label"].get<std::string>().find("over 13 scenarios"),
            std::string::npos);
  std::size_t on = 0;
  for (std::size_t i = 0; i < doc["points"].size(); ++i) {
    EXPECT_EQ(doc["points"][i]["in_sample"], run_front["points"][i]["goals"]) << i;
    EXPECT_EQ(doc["points"][i]["parameters"], run_front["points"][i]["parameters"]) << i;
    on += doc["points"][i]["dominated"].get<bool>() ? 0 : 1;
  }
  ASSERT_GT(on, 0u);
  // pick on the held-out knee: the point's parameters, its run values, its held-out values,
  // and a warning for each soft goal worse held out than in the run beyond its floor.
  const json g = tune::pick_gains(dir / "held", "knee");
  const std::size_t k = g["goals"]["front"]["index"];
  EXPECT_EQ(k, doc["picked"]["index"].get<std::size_t>());
  const json& point = doc["points"][k];
  EXPECT_FALSE(point["dominated"].get<bool>());
  EXPECT_EQ(g["tuned"]["Kp"], point["parameters"]["Kp"]);
  EXPECT_EQ(g["goals"]["goals"][0]["value"], point["in_sample"][0]);
  EXPECT_EQ(g["goals"]["front"]["held_out"]["goals"], point["goals"]);
  std::size_t worse = 0;
  for (std::size_t s = 0; s < 2; ++s) {
    const double in = point["in_sample"][s], out = point["goals"][s];
    const double floor = point["noise_floor"][s].is_null() ? 0.0 : point["noise_floor"][s].get<double>();
    worse += (out - in) / std::abs(in) > floor ? 1 : 0;
  }
  EXPECT_EQ(g["goals"]["front"]["held_out"]["warnings"].size(), worse);
  EXPECT_NO_THROW(runtime::parse_gains(g, "held-out knee"));
  // The run's values are checked against its trials.csv.
  json forged = doc;
  forged["points"][0]["in_sample"][0] = 1e-30;
  tune::write_file_atomic(dir / "held" / "front.json", forged.dump());
  try {
    tune::pick_gains(dir / "held", "index:0");
    ADD_FAILURE() << "a forged in_sample was taken";
  } catch (const InputError& e) {
    EXPECT_EQ(e.errors().at(0).path, "/points/0/in_sample/0") << e.what();
  }
  // Nor is a held-out front: it names its run.
  const CliResult again = run_cli("evaluate '" + (dir / "job.json").string() + "' --front '" +
                                      (dir / "held").string() + "' --no-figure --out '" +
                                      (dir / "y").string() + "'",
                                  dir);
  EXPECT_EQ(again.exit_code, 2) << again.err;
  EXPECT_NE(again.err.find("is a held-out front"), std::string::npos) << again.err;
  // A run of another job is no --front.
  json other = j;
  other["name"] = "another";
  tune::write_file_atomic(dir / "other.json", other.dump());
  const CliResult refused =
      run_cli("evaluate '" + (dir / "other.json").string() + "' --front '" +
                  (dir / "run").string() + "' --no-figure --out '" + (dir / "x").string() + "'",
              dir);
  EXPECT_EQ(refused.exit_code, 2) << refused.err;
  EXPECT_NE(refused.err.find("--front: "), std::string::npos) << refused.err;
}

// The held-out knee is taken in the held-out values' order: the run's order (A, B, C by the
// run's values) puts A first, but held out B is the least in the first goal; the line runs
// from B to C and the knee is A (in the run's order it would have been B).
TEST(Front, HeldOutKneeFollowsTheHeldOutValuesOrder) {
  const tune::Job job = tune::parse_job(front_job(), "front");
  const tune::Front run = tune::make_front(
      job, {trial(0, 1, 1000), trial(0, 10, 100), trial(0, 100, 10)});  // A, B, C
  ASSERT_EQ(run.points.size(), 3u);
  const auto at = [](double x, double y) { return std::vector<double>{std::pow(10.0, x),
                                                                      std::pow(10.0, y), 1.0}; };
  const tune::Front held = tune::held_out_front(
      job, run, {"run", 8, 100, 0.0}, {at(0.4, 0.6), at(0.3, 0.78), at(0.5, 0.0)}, {});
  for (const tune::FrontPoint& p : held.points) EXPECT_FALSE(p.dominated);
  EXPECT_EQ(held.picked, 0u);
  EXPECT_EQ(tune::pick_point(job, held, "knee"), 0u);
  EXPECT_EQ(tune::pick_point(job, held, "min:ise"), 1u);
}

TEST(Front, PickRules) {
  const tune::Job job = tune::parse_job(front_job(), "front");
  const std::vector<tune::Trial> trials = {trial(0, 1, 1000), trial(0, 10, 10), trial(0, 1000, 1)};
  const tune::Front f = tune::make_front(job, trials);
  EXPECT_EQ(tune::pick_point(job, f, "knee"), 1u);
  EXPECT_EQ(tune::pick_point(job, f, "min:ise"), 0u);
  EXPECT_EQ(tune::pick_point(job, f, "min:control_tv"), 2u);
  EXPECT_EQ(tune::pick_point(job, f, "index:2"), 2u);
  // The least ISE among the points whose control TV is at most 10 (10 and 1): ISE 10.
  EXPECT_EQ(tune::pick_point(job, f, "limit:control_tv<=10"), 1u);
  EXPECT_EQ(tune::pick_point(job, f, "limit:control_tv<=1e9"), 0u);
  for (const char* bad :
       {"index:3", "index:1.5", "index:0x2", "index: 1", "index:", "min:iae",
        "limit:control_tv<=0.5", "limit:control_tv", "limit:control_tv<=x",
        "limit:control_tv<=0x10", "limit:control_tv<=inf", "best"}) {
    try {
      tune::pick_point(job, f, bad);
      ADD_FAILURE() << bad << " was not refused";
    } catch (const InputError& e) {
      EXPECT_EQ(e.errors().at(0).path, "/rule") << bad;
    }
  }
}

TEST(Front, TwoGoalRunWritesANonDominatedFeasibleFrontTheSameOnOneAndTwoThreads) {
  const tune::Job job = tune::parse_job(front_job(), "front");
  const tune::TuningOutcome one = tuned(job, 1);
  ASSERT_TRUE(one.front);
  const auto files = tune::output_files(one);
  ASSERT_TRUE(files.count("front.json") && files.count("front.csv"));
  const json front = json::parse(files.at("front.json"));
  EXPECT_EQ(front["schema"], "ftctune.front/1");
  EXPECT_EQ(front["goals"].size(), 3u);
  EXPECT_EQ(front["space"], "log10");
  const json& points = front["points"];
  ASSERT_GE(points.size(), 2u);
  for (std::size_t i = 0; i < points.size(); ++i) {
    EXPECT_EQ(points[i]["feasible"], true);
    EXPECT_TRUE(points[i]["parameters"].contains("Kp"));
    EXPECT_TRUE(points[i]["parameters"].contains("switching_gain"));
    if (i > 0) {
      EXPECT_LT(points[i - 1]["goals"][0], points[i]["goals"][0]);
    }
    const auto vec = [&](std::size_t k) {
      return tune::ObjectiveVector{
          {points[k]["goals"][0].get<double>(), points[k]["goals"][1].get<double>()}, 0.0};
    };
    for (std::size_t k = 0; k < points.size(); ++k) {
      if (k != i) {
        EXPECT_FALSE(tune::pareto::dominates(vec(k), vec(i))) << i << " " << k;
      }
    }
  }
  // The gains are the picked point's, with the rule recorded.
  const json gains = tune::gains_document(one);
  const std::size_t picked = front["picked"]["index"];
  EXPECT_EQ(gains["tuned"]["Kp"], points[picked]["parameters"]["Kp"]);
  EXPECT_EQ(gains["goals"]["front"]["index"], picked);
  EXPECT_NE(gains["goals"]["rule"].get<std::string>().find("knee"), std::string::npos);
  // history.csv's hypervolume: non-decreasing, the last the front's.
  const std::string history = files.at("history.csv");
  EXPECT_NE(history.find(",hypervolume\n"), std::string::npos);
  ASSERT_EQ(one.hypervolume.size(), 4u);
  for (std::size_t i = 1; i < one.hypervolume.size(); ++i)
    EXPECT_GE(one.hypervolume[i], one.hypervolume[i - 1]);
  EXPECT_EQ(one.hypervolume.back(), front["hypervolume"].get<double>());
  // Every point carries the noise floor of each goal whose value is finite and not 0.
  for (std::size_t i = 0; i < points.size(); ++i)
    for (std::size_t k = 0; k < 3; ++k) {
      const double v = points[i]["goals"][k];
      EXPECT_EQ(points[i]["noise_floor"][k].is_number(), std::isfinite(v) && v != 0) << i << k;
    }
  // Each point lists as partners the points the rule joins it with, and each goal its words.
  const tune::Front read = tune::front_from_json(job, front);
  for (std::size_t a = 0; a < points.size(); ++a) {
    const std::vector<std::size_t>& partners = read.points[a].within_noise;
    for (std::size_t b = 0; b < points.size(); ++b) {
      if (a == b) continue;
      EXPECT_EQ(std::count(partners.begin(), partners.end(), b) == 1,
                tune::no_trade_off(read, a, b))
          << a << " " << b;
    }
  }
  for (std::size_t k = 0; k < 3; ++k)
    EXPECT_EQ(front["goals"][k]["label"], tune::front_goal(job, k).label);
  EXPECT_EQ(front["goals"][1]["label"], "control TV");
  // The picked point's is the tuned controller's alone on SPEC §14's R nudged copies, and so is
  // the run's objective noise floor; every point's re-runs are counted.
  {
    const tune::TuningProblem problem(job);
    tune::TbbEvaluator evaluator(1);
    std::vector<double> lo(3, INFINITY), hi(3, -INFINITY);
    double objective_lo = INFINITY, objective_hi = -INFINITY;
    for (int k = 0; k < one.noise_floor->repeats; ++k) {
      const tune::Evaluation e =
          problem
              .perturbed(one.seed, tune::kNoiseFloorStream + static_cast<std::uint64_t>(k),
                         one.noise_floor->perturbation)
              .evaluate(std::span<const sim::ControllerConfig>(&one.tuned_controller, 1),
                        evaluator)[0]
              .evaluation;
      objective_lo = std::min(objective_lo, e.objective);
      objective_hi = std::max(objective_hi, e.objective);
      for (std::size_t g = 0; g < 3; ++g) {
        lo[g] = std::min(lo[g], e.goals[g]);
        hi[g] = std::max(hi[g], e.goals[g]);
      }
    }
    for (std::size_t g = 0; g < 3; ++g)
      EXPECT_EQ(points[picked]["noise_floor"][g].get<double>(),
                (hi[g] - lo[g]) / std::abs(points[picked]["goals"][g].get<double>()))
          << g;
    EXPECT_EQ(one.noise_floor->objective_min, objective_lo);
    EXPECT_EQ(one.noise_floor->objective_max, objective_hi);
    // The trials the cache served (issue 43) ran nothing.
    const auto served = static_cast<std::size_t>(tune::cached_trials(one.trials));
    const auto listed = static_cast<std::int64_t>(one.trials.size() - served +
                                                  one.comparison.size() +
                                                  one.noise_floor->repeats * points.size());
    EXPECT_GE(one.simulations, listed);  // one scenario; at most one probe per parameter more
    EXPECT_LE(one.simulations, listed + 2);
  }

  const auto two = tune::output_files(tuned(job, 2));
  for (const char* f : {"front.json", "front.csv", "gains.json", "history.csv", "trials.csv"})
    EXPECT_EQ(two.at(f), files.at(f)) << f;

  // Resumed after iteration 1 of 3: the same bytes.
  const json state = checkpoint_after(job, 1);
  tune::RunOptions resume;
  resume.resume = &state;
  const auto resumed = tune::output_files(tuned(job, 2, std::nullopt, resume));
  for (const char* f : {"front.json", "front.csv", "gains.json", "history.csv", "trials.csv"})
    EXPECT_EQ(resumed.at(f), files.at(f)) << f;

  // pick: each rule's gains file loads in the runtime and holds its point.
  const auto dir = fresh_dir("pick");
  tune::write_output_files(files, dir);
  for (const std::string& rule :
       std::vector<std::string>{"knee", "min:ise", "min:control_tv", "index:1",
                                "limit:control_tv<=" + points[0]["goals"][1].dump()}) {
    const json g = tune::pick_gains(dir, rule);
    const std::size_t i = g["goals"]["front"]["index"];
    EXPECT_EQ(g["tuned"]["Kp"], points[i]["parameters"]["Kp"]) << rule;
    EXPECT_EQ(g["controller"]["switching_gain"], points[i]["parameters"]["switching_gain"]);
    EXPECT_EQ(g["goals"]["goals"][1]["value"], points[i]["goals"][1]) << rule;
    EXPECT_EQ(g.contains("noise_floor"), i == picked) << rule;
    EXPECT_NO_THROW(runtime::parse_gains(g, rule)) << rule;
  }
  EXPECT_EQ(tune::pick_gains(dir, "knee"), gains);
  EXPECT_EQ(tune::pick_gains(dir, "min:control_tv")["goals"]["front"]["index"], points.size() - 1);
  // The CLI: a file written whole, exit 2 for a rule that picks nothing.
  const CliResult ok = run_cli(
      "pick '" + dir.string() + "' --rule index:0 --out '" + (dir / "p0.json").string() + "'", dir);
  EXPECT_EQ(ok.exit_code, 0) << ok.err;
  EXPECT_EQ(runtime::read_gains(dir / "p0.json").tuned.size(), 2u);
  const CliResult bad = run_cli("pick '" + dir.string() + "' --rule min:iae", dir);
  EXPECT_EQ(bad.exit_code, 2);
  EXPECT_NE(bad.err.find("/rule"), std::string::npos) << bad.err;

  // Damaged files: each an InputError naming the file and the JSON path, exit 2.
  json bad_trial = front;
  bad_trial["points"][0]["trial"] = 100000;
  json no_goals = gains;
  no_goals["goals"]["goals"] = 3;
  const std::vector<std::tuple<std::string, std::string, std::string>> damaged = {
      {"gains.json", "[1, 2]", ""},
      {"gains.json", no_goals.dump(), "/goals/goals"},
      {"front.json", bad_trial.dump(), "/points/0/trial"}};
  for (const auto& [file, text, path] : damaged) {
    const auto broken = fresh_dir("pick-damaged");
    tune::write_output_files(files, broken);
    {
      std::ofstream f(broken / file);
      f << text;
    }
    try {
      tune::pick_gains(broken, "index:0");
      ADD_FAILURE() << file << " " << path << " was not refused";
    } catch (const InputError& e) {
      EXPECT_EQ(e.source(), (broken / file).string()) << path;
      ASSERT_FALSE(e.errors().empty());
      EXPECT_EQ(e.errors().at(0).path, path);
    }
    const CliResult refused = run_cli("pick '" + broken.string() + "' --rule index:0", broken);
    EXPECT_EQ(refused.exit_code, 2) << file << " " << path << ": " << refused.err;
  }
}

TEST(Front, WithoutAFeasibleTrialTheFrontIsEmptyAndTheGainsAreNotDeployable) {
  json j = front_job();
  j["goals"][2]["at_most"] = 1e-3;  // no gains keep the peak command under 1 mN m
  j["tuning"]["algorithm"]["iterations"] = 1;
  const tune::TuningOutcome r = tuned(tune::parse_job(j, "infeasible"), 1);
  ASSERT_TRUE(r.front);
  EXPECT_TRUE(r.front->points.empty());
  const auto files = tune::output_files(r);
  const json front = json::parse(files.at("front.json"));
  EXPECT_TRUE(front["points"].empty());
  EXPECT_TRUE(front["picked"].is_null());
  EXPECT_EQ(front["hypervolume"], 0.0);
  const json gains = tune::gains_document(r);
  EXPECT_EQ(gains["goals"]["feasible"], false);
  EXPECT_FALSE(gains["goals"].contains("front"));
  EXPECT_THROW(runtime::parse_gains(gains, "infeasible"), InputError);  // fitness < 0
  // The rule says why there is no front point, not the rule of one soft goal.
  EXPECT_NE(gains["goals"]["rule"].get<std::string>().find("front (front.json) is empty"),
            std::string::npos)
      << gains["goals"]["rule"];
}

TEST(Front, AReportOfARunWithAnEmptyFrontSaysNoPointMetTheHardGoals) {
  const auto dir = fresh_dir("front-empty-report");
  json j = front_job();
  j["goals"][2]["at_most"] = 1e-3;  // no gains keep the peak command under 1 mN m
  j["tuning"]["algorithm"]["iterations"] = 1;
  const CliResult r = run_job(dir, j, "--report", "out");
  // 3: the gains met no hard goal and must not be deployed; the report is written all the same.
  ASSERT_EQ(r.exit_code, 3) << r.err;
  ASSERT_TRUE(json::parse(slurp(dir / "out" / "front.json"))["points"].empty());
  const std::string html = slurp(dir / "out" / "report.html");
  EXPECT_NE(html.find("No trial of the run met the hard goals"), std::string::npos);
  EXPECT_FALSE(std::filesystem::exists(dir / "out" / "figures" / "front-pareto.png"));
  EXPECT_FALSE(std::filesystem::exists(dir / "out" / "figures" / "front-hypervolume.png"));
  // `ftctune report` of the same run, too.
  const CliResult again = run_cli("report '" + (dir / "out").string() + "'", dir);
  EXPECT_EQ(again.exit_code, 0) << again.err;
}

TEST(Front, RunWithTheRandomSearchBaselineWritesEveryFile) {
  // The baseline is random search in the registry's form, which searches for fronts too.
  const auto dir = fresh_dir("front-baseline");
  json j = front_job();
  j["tuning"]["algorithm"]["iterations"] = 1;
  const CliResult r = run_job(dir, j, "--baseline", "out");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  for (const char* f : {"front.json", "gains.json", "history.csv", "history-random.csv"})
    EXPECT_FALSE(slurp(dir / "out" / f).empty()) << f;
  // Its history: the header and the same two iterations as the run's.
  const std::string random = slurp(dir / "out" / "history-random.csv");
  EXPECT_EQ(std::count(random.begin(), random.end(), '\n'), 3) << random;
}

// A two-goal `run` lists the files it wrote, front.json and front.csv among them, and sums up
// the front: its size, its hypervolume, the point gains.json holds, and how to pick another.
TEST(Front, RunListsItsFrontFilesAndSumsUpTheFront) {
  const auto dir = fresh_dir("front-summary");
  json j = front_job();
  j["tuning"]["algorithm"]["iterations"] = 1;
  tune::write_file_atomic(dir / "job.json", j.dump());
  const std::string out = (dir / "out").string();
  const CliResult r = run_cli("run --no-checkpoint --threads 1 '" + (dir / "job.json").string() +
                                  "' --out '" + out + "'",
                              dir);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  // The progress log gives the front's size so far, not a "best J" of one corner of it.
  EXPECT_NE(r.err.find("iteration 1/1: front of "), std::string::npos) << r.err;
  EXPECT_EQ(r.err.find("best J"), std::string::npos) << r.err;
  EXPECT_NE(r.out.find("wrote " + out + "/{comparison.json, comparison.md, front.csv, front.json, "
                       "gains.json, history.csv, job.json, trials.csv, run.json} and "
                       "trajectories/"),
            std::string::npos)
      << r.out;
  const json front = json::parse(slurp(dir / "out" / "front.json"));
  const std::size_t picked = front["picked"]["index"];
  EXPECT_NE(r.out.find("front: " + std::to_string(front["points"].size()) +
                       " points, hypervolume "),
            std::string::npos)
      << r.out;
  EXPECT_NE(r.out.find("gains.json holds point " + std::to_string(picked) + " (the knee): ISE["),
            std::string::npos)
      << r.out;
  EXPECT_NE(r.out.find("another point: ftctune pick " + out + " --rule min:control_tv"),
            std::string::npos)
      << r.out;
  // After the last iteration the log says what the run still evaluates: the comparison of the
  // two compare entries, the job's own and the tuned, and 8 reruns of each point of the front.
  const std::size_t points = front["points"].size();
  EXPECT_NE(r.err.find("iterations done; now " + std::to_string(4 + 8 * points) +
                       " more evaluations of the 1 scenario: the comparison of 4 controllers and "
                       "the noise floor (8 reruns of each of the front's " +
                       std::to_string(points) + " points)"),
            std::string::npos)
      << r.err;
  EXPECT_LT(r.err.find("iteration 1/1: front of "), r.err.find("iterations done"));
}

TEST(Front, OneSoftGoalRunsWriteNoFront) {
  json j = short_table1_job();
  j["tuning"]["algorithm"]["iterations"] = 0;
  const auto files = tune::output_files(tuned(tune::parse_job(j, "one"), 1));
  EXPECT_EQ(files.count("front.json"), 0u);
  EXPECT_EQ(files.at("history.csv").find("hypervolume"), std::string::npos);
}

TEST(Front, IsTheSameBytesUnderEveryInstructionSet) {
  // The front, its hypervolume and the knee's gains do not depend on the instruction set the
  // simulations ran on (FTCTUNE_ISA; the child inherits the environment).
  const auto dir = fresh_dir("front-isa");
  json j = front_job();
  j["tuning"]["algorithm"]["iterations"] = 1;
  std::string front, gains;
  for (const sim::Isa isa : sim::supported_isas()) {
    const std::string name = sim::to_string(isa);
    ::setenv("FTCTUNE_ISA", name.c_str(), 1);
    const CliResult r = run_job(dir, j, "", name);
    ::unsetenv("FTCTUNE_ISA");
    ASSERT_EQ(r.exit_code, 0) << name << ": " << r.err;
    const std::string f = slurp(dir / name / "front.json"), g = slurp(dir / name / "gains.json");
    ASSERT_FALSE(f.empty());
    if (front.empty()) {
      front = f;
      gains = g;
    } else {
      EXPECT_EQ(f, front) << "front.json under FTCTUNE_ISA=" << name;
      EXPECT_EQ(g, gains) << "gains.json under FTCTUNE_ISA=" << name;
    }
  }
}
