// Scenario ensembles (SPEC §12): the random stream, the draw order, the loader's checks and the
// recoverability flag. Golden values come from a reference expansion written in Python from the
// spec's text alone (the stream, the draw order and the distributions), not from this code.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <functional>
#include <nlohmann/json.hpp>
#include <set>
#include <thread>

#include "cli_runner.hpp"
#include "ftc/sim/input_error.hpp"
#include "ftc/sim/plants.hpp"
#include "ftc/tune/job/ensemble.hpp"
#include "ftc/tune/job/job.hpp"

using nlohmann::json;
using namespace ftc;
using tune::SplitMix64;

namespace {

json robust_job() {
  std::ifstream in(std::string(FTC_SOURCE_DIR) + "/jobs/robust-faults.json");
  return json::parse(in);
}

tune::Job parse(const json& j) { return tune::parse_job(j, "job.json"); }

std::vector<FieldError> ensemble_errors(const json& j,
                                        const std::optional<std::filesystem::path>& dir = {}) {
  try {
    tune::parse_job(j, "job.json", dir);
  } catch (const InputError& e) {
    return e.errors();
  }
  return {};
}

}  // namespace

TEST(SplitMix64, FirstDrawsOfSeedsZeroAndOneMatchTheSpec) {
  // Member 0: s0 = mix(seed XOR mix(1)); each draw adds the golden gamma and mixes.
  SplitMix64 a = SplitMix64::member(0, 0);
  EXPECT_EQ(a.next_bits(), 0x4181b152fb77616fULL);
  EXPECT_EQ(a.next_bits(), 0x169c646d52269d62ULL);
  EXPECT_EQ(a.next_bits(), 0x4a5de8d8d53b7280ULL);
  SplitMix64 b = SplitMix64::member(1, 0);
  EXPECT_EQ(b.next_bits(), 0x275f2ae791fef8a1ULL);
  EXPECT_EQ(b.next_bits(), 0x0091f1cf4437d33eULL);
  EXPECT_EQ(b.next_bits(), 0xee57a3a974d5f617ULL);
  SplitMix64 c = SplitMix64::member(1, 0);
  EXPECT_EQ(c.uniform(), 0.1537958922726793);
  EXPECT_EQ(c.uniform(), 0.002226937391440531);
  EXPECT_EQ(c.uniform(), 0.9310247696601761);
}

TEST(Ensemble, MembersMatchAReferenceExpansionOfTheSpec) {
  const tune::Job job = parse(robust_job());
  // Member 3 of seed 7: one abrupt bias fault (slot 2 drawn and discarded).
  const sim::Scenario m3 = tune::ensemble_member(job, 7, 3);
  EXPECT_EQ(m3.name, "paper-3");
  ASSERT_EQ(m3.true_values.size(), 1u);
  ASSERT_NE(m3.true_value("inertia"), nullptr);
  const std::vector<double>& i3 = *m3.true_value("inertia");
  ASSERT_EQ(i3.size(), 3u);
  EXPECT_EQ(i3[0], 20.625084207978077);
  EXPECT_EQ(i3[1], 16.777898040398846);
  EXPECT_EQ(i3[2], 13.54051055855346);
  ASSERT_EQ(m3.faults.size(), 1u);
  const sim::Fault& b = m3.faults[0];
  EXPECT_EQ(b.actuator, 1);
  EXPECT_EQ(b.type, sim::FaultType::bias);
  EXPECT_EQ(b.profile.type, sim::FaultProfileType::abrupt);
  EXPECT_EQ(b.onset, 9.087384142986163);
  EXPECT_EQ(b.offset, -2.270544850527533);
  EXPECT_EQ(b.amplitude, 9.839507612303125);
  EXPECT_EQ(b.frequency, 0.8970453709406235);
  EXPECT_EQ(b.phase, 0.9478611147061534);
  // Member 12: an incipient loss of effectiveness, then a stuck actuator drawn from the three
  // left (1 was taken, so floor(u·3) indexes [2, 3, 4]).
  const sim::Scenario m12 = tune::ensemble_member(job, 7, 12);
  ASSERT_NE(m12.true_value("inertia"), nullptr);
  const std::vector<double>& i12 = *m12.true_value("inertia");
  ASSERT_EQ(i12.size(), 3u);
  EXPECT_EQ(i12[0], 19.23771134634238);
  EXPECT_EQ(i12[1], 18.078988098774534);
  EXPECT_EQ(i12[2], 15.298535397997906);
  ASSERT_EQ(m12.faults.size(), 2u);
  EXPECT_EQ(m12.faults[0].actuator, 1);
  EXPECT_EQ(m12.faults[0].type, sim::FaultType::loss_of_effectiveness);
  EXPECT_EQ(m12.faults[0].profile.type, sim::FaultProfileType::incipient);
  EXPECT_EQ(m12.faults[0].profile.rate, 4.795016293024455);
  EXPECT_EQ(m12.faults[0].onset, 5.643551795739229);
  EXPECT_EQ(m12.faults[0].fraction, 0.6164723848764094);
  EXPECT_EQ(m12.faults[1].actuator, 4);
  EXPECT_EQ(m12.faults[1].type, sim::FaultType::stuck);
  EXPECT_EQ(m12.faults[1].onset, 7.149049129067784);
  EXPECT_EQ(m12.faults[1].value, 0.0716206999165272);
}

TEST(Ensemble, FaultCountFollowsTheEleventhDrawAtTheEdges) {
  json j = robust_job();
  for (const auto& [lo, hi] : std::vector<std::pair<int, int>>{{0, 0}, {0, 4}, {4, 4}, {2, 3}}) {
    j["ensemble"]["faults"]["count"] = {lo, hi};
    const tune::Job job = parse(j);
    std::set<std::size_t> seen;
    for (std::int64_t k = 0; k < 200; ++k) {
      // Draws 0-9 are the scales; draw 10 decides the count: lo + floor(u (hi - lo + 1)).
      SplitMix64 r = SplitMix64::member(7, static_cast<std::uint64_t>(k));
      for (int i = 0; i < 10; ++i) r.uniform();
      const auto expected = static_cast<std::size_t>(
          std::min(hi, lo + static_cast<int>(r.uniform() * (hi - lo + 1))));
      const std::size_t n = tune::ensemble_member(job, 7, k).faults.size();
      EXPECT_EQ(n, expected) << "count [" << lo << ", " << hi << "], member " << k;
      seen.insert(n);
    }
    // 200 members reach both ends of the range.
    EXPECT_EQ(*seen.begin(), static_cast<std::size_t>(lo));
    EXPECT_EQ(*seen.rbegin(), static_cast<std::size_t>(hi));
  }
}

TEST(Ensemble, ActuatorsAreDrawnWithoutReplacementInListedOrder) {
  json j = robust_job();
  j["ensemble"]["faults"]["count"] = {3, 3};
  j["ensemble"]["faults"]["actuators"] = {4, 2, 3};
  const tune::Job job = parse(j);
  for (std::int64_t k = 0; k < 50; ++k) {
    const sim::Scenario m = tune::ensemble_member(job, 7, k);
    std::vector<int> left = {4, 2, 3};  // listed order, not numeric order
    SplitMix64 r = SplitMix64::member(7, static_cast<std::uint64_t>(k));
    for (int i = 0; i < 11; ++i) r.uniform();
    ASSERT_EQ(m.faults.size(), 3u);
    for (const sim::Fault& f : m.faults) {
      const double u = r.uniform();
      for (int i = 0; i < 10; ++i) r.uniform();
      const auto idx = static_cast<std::size_t>(u * static_cast<double>(left.size()));
      EXPECT_EQ(f.actuator, left[idx]) << "member " << k;
      left.erase(left.begin() + static_cast<long>(idx));
    }
  }
}

TEST(Ensemble, ChoicesFollowTheCanonicalOrderNotTheJsonOrder) {
  const tune::Choice c{{1.0, 0.0, 1.0}};  // bias, loss_of_effectiveness, stuck
  EXPECT_EQ(c.pick(0.0), 0u);
  EXPECT_EQ(c.pick(0.4999), 0u);
  EXPECT_EQ(c.pick(0.5), 2u);  // first name whose cumulative weight exceeds u·W
  EXPECT_EQ(c.pick(0.9999), 2u);
  const tune::Choice only_middle{{0.0, 3.0, 0.0}};
  EXPECT_EQ(only_middle.pick(0.0), 1u);
  EXPECT_EQ(only_middle.pick(0.9999), 1u);
  // The same weights written in another key order expand to the same members.
  json a = robust_job(), b = robust_job();
  a["ensemble"]["faults"]["type"] = json::parse(R"({"bias": 1, "stuck": 2})");
  b["ensemble"]["faults"]["type"] = json::parse(R"({"stuck": 2, "bias": 1})");
  EXPECT_EQ(tune::to_json(tune::expand_ensemble(parse(a), 7, 20).back()),
            tune::to_json(tune::expand_ensemble(parse(b), 7, 20).back()));
}

TEST(Ensemble, ExpansionDoesNotDependOnThreadsOrOrder) {
  const tune::Job job = parse(robust_job());
  const std::vector<sim::Scenario> serial = tune::expand_ensemble(job);
  ASSERT_EQ(serial.size(), 100u);
  // Members drawn backwards on two threads are the same members.
  std::vector<json> parallel(serial.size());
  const auto half = [&](std::int64_t from, std::int64_t to) {
    for (std::int64_t k = to - 1; k >= from; --k)
      parallel[static_cast<std::size_t>(k)] = tune::to_json(tune::ensemble_member(job, 7, k));
  };
  std::thread t1(half, 0, 50), t2(half, 50, 100);
  t1.join();
  t2.join();
  for (std::size_t k = 0; k < serial.size(); ++k)
    EXPECT_EQ(tune::to_json(serial[k]), parallel[k]) << "member " << k;
}

TEST(Ensemble, EveryMalformedEnsembleIsReportedWithItsPath) {
  struct Case {
    const char* what;
    std::function<void(json&)> mutate;
    const char* path;
    const char* message;
  };
  const std::vector<Case> cases = {
      {"weights all zero",
       [](json& j) {
         j["ensemble"]["faults"]["type"] = {{"bias", 0}, {"stuck", 0}};
       },
       "/ensemble/faults/type", "must not all be zero"},
      {"negative scale",
       [](json& j) {
         j["ensemble"]["inertia_scale"] = {{"uniform", {-0.5, 1}}};
       },
       "/ensemble/inertia_scale/uniform/0", "must be > 0"},
      {"reversed range",
       [](json& j) {
         j["ensemble"]["inertia_scale"] = {{"uniform", {1.2, 0.8}}};
       },
       "/ensemble/inertia_scale/uniform", "lower end 1.2 is above upper end 0.8"},
      {"log_uniform from 0",
       [](json& j) {
         j["ensemble"]["faults"]["frequency"] = {{"log_uniform", {0, 3}}};
       },
       "/ensemble/faults/frequency/log_uniform/0", "must be > 0 for a log-uniform"},
      {"more faults than actuators",
       [](json& j) {
         j["ensemble"]["faults"]["count"] = {1, 5};
       },
       "/ensemble/faults/count", "upper bound 5 exceeds the 4 listed actuators"},
      {"unknown base", [](json& j) { j["ensemble"]["base"] = "nope"; }, "/ensemble/base",
       "no scenario is named \"nope\""},
      {"actuator 5",
       [](json& j) {
         j["ensemble"]["faults"]["actuators"] = {1, 5};
       },
       "/ensemble/faults/actuators/1", "actuator 5 does not exist"},
      {"actuator 0",
       [](json& j) {
         j["ensemble"]["faults"]["actuators"] = {0, 1};
       },
       "/ensemble/faults/actuators/0", "actuator 0 does not exist"},
      {"count 0", [](json& j) { j["ensemble"]["count"] = 0; }, "/ensemble/count",
       "must be an integer in 1..1000000 (got 0)"},
      {"count above a million", [](json& j) { j["ensemble"]["count"] = 1000001; },
       "/ensemble/count", "must be an integer in 1..1000000 (got 1000001)"},
      {"unknown profile",
       [](json& j) {
         j["ensemble"]["faults"]["profile"] = {{"sudden", 1}};
       },
       "/ensemble/faults/profile/sudden", "unknown name (known: abrupt, incipient)"},
      {"unknown key", [](json& j) { j["ensemble"]["members"] = 3; }, "/ensemble/members", ""},
  };
  for (const Case& c : cases) {
    json j = robust_job();
    c.mutate(j);
    const std::vector<FieldError> errs = ensemble_errors(j);
    const bool found = std::any_of(errs.begin(), errs.end(), [&](const FieldError& e) {
      return e.path == c.path && e.message.find(c.message) != std::string::npos;
    });
    EXPECT_TRUE(found) << c.what << ": got " << (errs.empty() ? "no error" : to_string(errs[0]));
  }
  // Every error at once, not the first only.
  json j = robust_job();
  j["ensemble"]["count"] = 0;
  j["ensemble"]["base"] = "nope";
  j["ensemble"]["faults"]["count"] = {3, 1};
  EXPECT_GE(ensemble_errors(j).size(), 3u);
}

TEST(Ensemble, ScenariosFileMustExistAndBeAScenariosFile) {
  const std::filesystem::path dir = ftc::testing::fresh_dir("scenarios-file");
  std::ofstream(dir / "job-schema.json") << R"({"schema": "ftctune.job/1"})";
  json j = robust_job();
  j["scenarios"] = {{"file", "missing.json"}};
  std::vector<FieldError> errs = ensemble_errors(j, dir);
  ASSERT_EQ(errs.size(), 1u) << to_string(errs[0]);  // and not what follows from it
  EXPECT_EQ(errs[0].path, "/scenarios/file");
  EXPECT_NE(errs[0].message.find("cannot open"), std::string::npos);
  j["scenarios"] = {{"file", "job-schema.json"}};
  errs = ensemble_errors(j, dir);
  ASSERT_EQ(errs.size(), 1u);
  EXPECT_NE(errs[0].message.find("not a scenarios file (ftctune.scenarios/1)"), std::string::npos);
}

TEST(Ensemble, CommandWritesMembersThatAJobLoadsBack) {
  const std::filesystem::path dir = ftc::testing::fresh_dir("ensemble-cmd");
  const std::string members = (dir / "members.json").string();
  const ftc::testing::CliResult r = ftc::testing::run_cli(
      "ensemble jobs/robust-faults.json --seed 11 --count 30 --out " + members, dir);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("wrote 30 members of robust-faults (seed 11,"), std::string::npos) << r.out;
  const json doc = json::parse(ftc::testing::slurp(members));
  EXPECT_EQ(doc["schema"], "ftctune.scenarios/1");
  EXPECT_EQ(doc["seed"], 11);
  ASSERT_EQ(doc["scenarios"].size(), 30u);
  // A job naming the file simulates exactly the members the ensemble draws with that seed.
  json j = robust_job();
  j.erase("ensemble");
  j["scenarios"] = {{"file", "members.json"}};
  const tune::Job loaded = tune::parse_job(j, "job.json", dir);
  const tune::Job job = parse(robust_job());
  const std::unique_ptr<sim::AnyPlant> plant = sim::make_plant(job.plant);
  ASSERT_EQ(loaded.scenarios.size(), 30u);
  for (std::int64_t k = 0; k < 30; ++k) {
    const sim::Scenario m = tune::ensemble_member(job, 11, k);
    EXPECT_EQ(tune::to_json(loaded.scenarios[static_cast<std::size_t>(k)]), tune::to_json(m));
    EXPECT_EQ(doc["scenarios"][static_cast<std::size_t>(k)]["recoverable"], plant->recoverable(m));
  }
  // A file whose recoverable flag was edited is refused.
  json edited = doc;
  edited["scenarios"][0]["recoverable"] = !doc["scenarios"][0]["recoverable"].get<bool>();
  std::ofstream(dir / "members.json") << edited.dump();
  const std::vector<FieldError> errs = ensemble_errors(j, dir);
  ASSERT_EQ(errs.size(), 1u);
  EXPECT_EQ(errs[0].path, "/scenarios/0/recoverable");
}

// Found by fuzz_job: the canonical JSON (what the service stores and its worker reads) wrote
// "actuators": [] for faults that name none, which the loader refuses.
TEST(Ensemble, FaultsWithoutActuatorsReadBackFromTheCanonicalJson) {
  json j = robust_job();
  j["ensemble"]["faults"].erase("actuators");
  j["ensemble"]["faults"]["count"] = {1, 4};
  const tune::Job job = parse(j);
  const json canonical = tune::to_json(job);
  EXPECT_FALSE(canonical["ensemble"]["faults"].contains("actuators")) << canonical.dump();
  const tune::Job again = tune::parse_job(canonical, "canonical");
  EXPECT_EQ(tune::to_json(again).dump(), canonical.dump());
  EXPECT_EQ(tune::to_json(tune::ensemble_member(again, 7, 3)),
            tune::to_json(tune::ensemble_member(job, 7, 3)));
}

// Found by fuzz_ensemble: a base scenario named with 100 characters was accepted, but its
// members' names are longer than a scenario name may be, so the file `ftctune ensemble` wrote
// was refused by the same job.
TEST(Ensemble, MemberNamesLongerThanAScenarioNameAreRefused) {
  const std::string base(98, 'b');
  json j = robust_job();
  j["scenarios"][0]["name"] = base;
  j["ensemble"]["base"] = base;
  j["ensemble"]["count"] = 10;  // the longest member is <base>-9: 100 characters
  EXPECT_TRUE(ensemble_errors(j).empty());
  j["ensemble"]["count"] = 11;  // <base>-10: 101
  std::vector<FieldError> errs = ensemble_errors(j);
  ASSERT_EQ(errs.size(), 1u);
  EXPECT_EQ(errs[0].path, "/ensemble/base");
  EXPECT_NE(errs[0].message.find("\"" + base + "-10\" would be longer than 100 characters"),
            std::string::npos)
      << errs[0].message;
  // Without a base the first scenario is it; a --count above the job's is checked the same way.
  j["ensemble"].erase("base");
  errs = ensemble_errors(j);
  ASSERT_EQ(errs.size(), 1u);
  EXPECT_EQ(errs[0].path, "/scenarios/0/name");
  j["ensemble"]["count"] = 10;
  EXPECT_THROW(tune::ensemble_count(parse(j), 11), InputError);
  EXPECT_EQ(tune::ensemble_count(parse(j), 10), 10);
}

// Found by fuzz_ensemble: a disturbance amplitude of 1e300 scaled by up to 1.8e19 gave members
// an infinite amplitude, so the job was accepted and its members file refused. The ends of each
// scale's range are checked against the base, and a uniform range too wide to draw from is
// refused.
TEST(Ensemble, ScalesThatWouldTakeAMemberOutOfRangeAreRefused) {
  const auto only_error = [](const json& j) {
    const std::vector<FieldError> errs = ensemble_errors(j);
    return errs.size() == 1 ? errs[0] : FieldError{"", std::to_string(errs.size()) + " errors"};
  };
  json j = robust_job();
  j["scenarios"][0]["disturbance"][1]["amplitude"] = 1e300;
  EXPECT_TRUE(ensemble_errors(j).empty());  // unscaled, 1e300 is a valid amplitude
  j["ensemble"]["disturbance_scale"] = {{"uniform", {0.5, 1.8446744073709552e19}}};
  FieldError e = only_error(j);
  EXPECT_EQ(e.path, "/ensemble/disturbance_scale");
  EXPECT_NE(e.message.find("/disturbance/1/amplitude"), std::string::npos) << e.message;

  j = robust_job();
  j["ensemble"]["inertia_scale"] = {{"log_uniform", {0.5, 1e307}}};
  e = only_error(j);
  EXPECT_EQ(e.path, "/ensemble/inertia_scale");
  EXPECT_NE(e.message.find("a member scaled by 1e+307 would have /inertia"), std::string::npos)
      << e.message;

  j = robust_job();
  j["ensemble"]["initial_state_scale"] = -1.5e308;  // times the state's 1.5: -inf
  EXPECT_EQ(only_error(j).path, "/ensemble/initial_state_scale");

  j = robust_job();
  j["ensemble"]["faults"]["offset"] = {{"uniform", {-1e308, 1e308}}};
  e = only_error(j);
  EXPECT_EQ(e.path, "/ensemble/faults/offset/uniform");
  EXPECT_NE(e.message.find("too wide"), std::string::npos) << e.message;
  j["ensemble"]["faults"]["offset"] = {{"uniform", {-1e307, 1e307}}};
  EXPECT_TRUE(ensemble_errors(j).empty());
}

TEST(Ensemble, CommandRefusesAJobWithoutEnsemble) {
  const ftc::testing::CliResult r =
      ftc::testing::run_cli("ensemble jobs/table1.json", ftc::testing::fresh_dir("ensemble-none"));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("/ensemble: the job has no ensemble to expand"), std::string::npos) << r.err;
}

TEST(Recoverability, TwoStuckActuatorsOfFourLeaveTheSpacecraftUncontrollable) {
  const tune::Job job = parse(robust_job());
  const std::unique_ptr<sim::AnyPlant> plant = sim::make_plant(job.plant);
  sim::Scenario s = job.scenarios[0];
  sim::Fault stuck;
  stuck.type = sim::FaultType::stuck;
  stuck.onset = 5;
  stuck.actuator = 1;
  s.faults = {stuck};
  EXPECT_TRUE(plant->recoverable(s));  // three working actuators still span the three axes
  stuck.actuator = 3;
  s.faults.push_back(stuck);
  EXPECT_FALSE(plant->recoverable(s));
  // A total loss of effectiveness is as bad as stuck; a partial one is not.
  s.faults[1].type = sim::FaultType::loss_of_effectiveness;
  s.faults[1].fraction = 1.0;
  EXPECT_FALSE(plant->recoverable(s));
  s.faults[1].fraction = 0.95;
  EXPECT_TRUE(plant->recoverable(s));
  // A bias leaves the actuator acting.
  s.faults[1].type = sim::FaultType::bias;
  EXPECT_TRUE(plant->recoverable(s));
}

TEST(Ensemble, BadEnsembleOrScenariosFileExitsTwoWithThePath) {
  const std::filesystem::path dir = ftc::testing::fresh_dir("ensemble-exit");
  json j = robust_job();
  j["ensemble"]["faults"]["actuators"] = json::array();
  std::ofstream(dir / "bad.json") << j.dump();
  ftc::testing::CliResult r =
      ftc::testing::run_cli("validate '" + (dir / "bad.json").string() + "'", dir);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("/ensemble/faults/actuators: must list at least one actuator"),
            std::string::npos)
      << r.err;
  // A scenarios file whose schema is not even a string.
  std::ofstream(dir / "odd.json") << R"({"schema": 7, "scenarios": []})";
  j = robust_job();
  j["scenarios"] = {{"file", "odd.json"}};
  std::ofstream(dir / "job.json") << j.dump();
  r = ftc::testing::run_cli("run '" + (dir / "job.json").string() + "'", dir);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("/scenarios/file: "), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("is 7, not a scenarios file"), std::string::npos) << r.err;
  // --count that would give a member the name of a listed scenario.
  j = robust_job();
  json other = j["scenarios"][0];
  other["name"] = "paper-150";
  j["scenarios"].push_back(other);
  std::ofstream(dir / "clash.json") << j.dump();
  r = ftc::testing::run_cli("ensemble '" + (dir / "clash.json").string() + "' --count 200", dir);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("/scenarios/1/name"), std::string::npos) << r.err;
}

TEST(Ensemble, EveryPlantDrawsSixInitialStateFactors) {
  // SPEC §12 fixes the draw order for any plant: on the two-link arm (four state components)
  // the disturbance factor is still the tenth draw.
  std::ifstream in(std::string(FTC_SOURCE_DIR) + "/jobs/manipulator.json");
  json j = json::parse(in);
  j["ensemble"] = {{"count", 3}, {"seed", 5}, {"disturbance_scale", {{"uniform", {0, 1}}}}};
  if (j["scenarios"][0]["disturbance"].empty())
    j["scenarios"][0]["disturbance"] = {{{"axis", 1}, {"amplitude", 1.0}, {"frequency", 1.0}}};
  const tune::Job job = parse(j);
  const double a = job.scenarios[0].disturbance[0].amplitude;
  for (std::int64_t k = 0; k < 3; ++k) {
    SplitMix64 r = SplitMix64::member(5, static_cast<std::uint64_t>(k));
    for (int i = 0; i < 9; ++i) r.uniform();
    EXPECT_EQ(tune::ensemble_member(job, 5, k).disturbance[0].amplitude, a * r.uniform());
  }
}

// `ftctune ensemble` writes its members one at a time (memory does not grow with the count),
// and the bytes are those of the whole document's dump(2), to standard output and to --out.
TEST(Ensemble, StreamedScenariosFileIsTheWholeDocumentsDump) {
  const auto dir = ftc::testing::fresh_dir("ensemble-stream");
  for (const char* count : {"1", "7"}) {
    const ftc::testing::CliResult r =
        ftc::testing::run_cli(std::string("ensemble jobs/robust-faults.json --count ") + count, dir);
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const json doc = json::parse(r.out);
    EXPECT_EQ(r.out, doc.dump(2) + "\n") << count;
    EXPECT_EQ(doc["scenarios"].size(), static_cast<std::size_t>(std::stoi(count)));
    EXPECT_EQ(doc["schema"], "ftctune.scenarios/1");
    const auto file = dir / (std::string("members-") + count + ".json");
    ASSERT_EQ(ftc::testing::run_cli(std::string("ensemble -q jobs/robust-faults.json --count ") +
                                        count + " --out '" + file.string() + "'",
                                    dir)
                  .exit_code,
              0);
    EXPECT_EQ(ftc::testing::slurp(file), r.out) << count;
  }
}

// Each plant declares its uncertain parameters; a member carries the true values of each (the
// base's or the plant's, by its factors), and a plant that declares none gets none.
TEST(Ensemble, MembersScaleThePlantsDeclaredUncertainParameters) {
  for (const sim::PlantKind& kind : sim::plant_kinds())
    for (const sim::UncertainParameter& u : kind.uncertain) {
      SCOPED_TRACE(kind.model + " " + u.parameter);
      ASSERT_NE(kind.offset(u.parameter), std::string_view::npos) << "not a parameter";
      const std::size_t values = kind.parameter_values(kind.defaults(), u.parameter).size();
      if (u.per_actuator)  // drawn per actuator (below), one slot per actuator the kernels have
        EXPECT_EQ(values, static_cast<std::size_t>(kind.actuators));
      else if (u.scaling == sim::Scaling::elementwise)
        EXPECT_LE(values, tune::kParameterFactors) << "more values than an ensemble draws factors";
      else  // a 3×3 tensor, one factor per axis
        EXPECT_EQ(values, tune::kParameterFactors * tune::kParameterFactors);
    }
  EXPECT_EQ(sim::find_plant_kind("manipulator")->uncertain_names(), "none");
  EXPECT_EQ(sim::find_plant_kind("spacecraft")->uncertain_names(), "inertia");

  std::ifstream in(std::string(FTC_SOURCE_DIR) + "/jobs/hexarotor.json");
  json j = json::parse(in);
  j["ensemble"] = {{"count", 3}, {"seed", 5}, {"inertia_scale", {{"uniform", {0.5, 1.5}}}}};
  const tune::Job hex = parse(j);
  const sim::PlantKind& kind = *sim::find_plant_kind("hexarotor");
  const std::vector<double> nominal = kind.parameter_values(hex.plant.values, "inertia");
  const sim::Scenario m = tune::ensemble_member(hex, 5, 1);
  ASSERT_EQ(m.true_values.size(), 1u);
  ASSERT_NE(m.true_value("inertia"), nullptr);
  // The first 3 draws of member 1's stream, through the scale's distribution, axis by axis.
  SplitMix64 r = SplitMix64::member(5, 1);
  for (std::size_t i = 0; i < 3; ++i)
    EXPECT_EQ((*m.true_value("inertia"))[i], nominal[i] * (0.5 + r.uniform()));
  // Unscaled, a member still writes the plant's true inertia (SPEC §12).
  j["ensemble"].erase("inertia_scale");
  EXPECT_EQ(*tune::ensemble_member(parse(j), 5, 1).true_value("inertia"), nominal);

  std::ifstream arm_in(std::string(FTC_SOURCE_DIR) + "/jobs/manipulator.json");
  json arm = json::parse(arm_in);
  arm["ensemble"] = {{"count", 3}, {"seed", 5}};
  EXPECT_TRUE(tune::ensemble_member(parse(arm), 5, 1).true_values.empty());

  // The elementwise rule: value i times factor i.
  std::vector<double> v{2, 3, 4};
  sim::PlantKind::scale(kind.uncertain[0], v, std::array<double, 3>{0.5, 2, 1});
  EXPECT_EQ(v, (std::vector<double>{1, 6, 4}));

  // A full tensor (rigid_body) is scaled as S J S, S = diag(√s_i), by the same 3 draws: the
  // diagonal by s_i, the products of inertia by √(s_i s_k), so the member's tensor stays
  // symmetric.
  std::ifstream sat_in(std::string(FTC_SOURCE_DIR) + "/jobs/smallsat-pyramid.json");
  json sat = json::parse(sat_in);
  sat["ensemble"] = {{"count", 3}, {"seed", 5}, {"inertia_scale", {{"uniform", {0.5, 1.5}}}}};
  const tune::Job body = parse(sat);
  const std::vector<double> J =
      sim::find_plant_kind("rigid_body")->parameter_values(body.plant.values, "inertia");
  const sim::Scenario b = tune::ensemble_member(body, 5, 1);
  ASSERT_NE(b.true_value("inertia"), nullptr);
  const std::vector<double>& T = *b.true_value("inertia");
  ASSERT_EQ(T.size(), 9u);
  SplitMix64 q = SplitMix64::member(5, 1);
  double f[3];
  for (double& x : f) x = 0.5 + q.uniform();
  for (std::size_t i = 0; i < 3; ++i)
    for (std::size_t k = 0; k < 3; ++k) {
      EXPECT_EQ(T[3 * i + k], T[3 * k + i]) << i << k;
      EXPECT_EQ(T[3 * i + k], J[3 * i + k] * (i == k ? f[i] : std::sqrt(f[i] * f[k]))) << i << k;
    }
}

// SPEC §17: after §12's draws (with faults: 10, the count and 11 per slot), m actuator scales
// then m misalignments; a member's scale is the base's times its draw, its misalignment the
// base's plus its draw. The draws are taken whether asked for or not, and a job without the keys
// expands to the same members as before.
TEST(Ensemble, ActuatorScalesThenMisalignmentsAreDrawnAfterTheFaults) {
  std::ifstream in(std::string(FTC_SOURCE_DIR) + "/jobs/smallsat-pyramid.json");
  json sat = json::parse(in);
  sat["scenarios"][0]["actuator_scale"] = {1.0, 0.8, 1.0, 1.0};
  sat["ensemble"] = {{"count", 4},
                     {"seed", 9},
                     {"actuator_scale", {{"uniform", {0.7, 1.0}}}},
                     {"actuator_misalignment", {{"uniform", {-0.05, 0.05}}}},
                     {"faults", {{"count", {0, 1}}, {"type", {{"stuck", 1}}}}}};
  const tune::Job job = parse(sat);
  for (std::int64_t k = 0; k < 4; ++k) {
    const sim::Scenario m = tune::ensemble_member(job, 9, k);
    SplitMix64 r = SplitMix64::member(9, static_cast<std::uint64_t>(k));
    r.skip(3 + 6 + 1 + 1 + 11);  // §12: inertia, state, disturbance, fault count, one slot
    ASSERT_NE(m.true_value("actuator_scale"), nullptr);
    ASSERT_NE(m.true_value("actuator_misalignment"), nullptr);
    const std::vector<double> base_scale{1.0, 0.8, 1.0, 1.0};
    for (std::size_t j = 0; j < 4; ++j)
      EXPECT_EQ((*m.true_value("actuator_scale"))[j], base_scale[j] * (0.7 + (1.0 - 0.7) * r.uniform()))
          << k << " " << j;
    for (std::size_t j = 0; j < 4; ++j)
      EXPECT_EQ((*m.true_value("actuator_misalignment"))[j], 0.0 + (-0.05 + 0.1 * r.uniform()))
          << k << " " << j;
  }
  // Without the keys: the base's, untouched; and the members of a job without them are as
  // before (no per-actuator values written).
  sat["ensemble"].erase("actuator_scale");
  sat["ensemble"].erase("actuator_misalignment");
  const sim::Scenario plain = tune::ensemble_member(parse(sat), 9, 2);
  EXPECT_EQ(*plain.true_value("actuator_scale"), (std::vector<double>{1.0, 0.8, 1.0, 1.0}));
  EXPECT_EQ(plain.true_value("actuator_misalignment"), nullptr);
  sat["scenarios"][0].erase("actuator_scale");
  const sim::Scenario none = tune::ensemble_member(parse(sat), 9, 2);
  EXPECT_EQ(none.true_value("actuator_scale"), nullptr);
  EXPECT_EQ(none.true_values.size(), 1u);  // the inertia, as every member writes it

  // Refused at their paths: a plant without them, a draw that would leave the range.
  json table1 = robust_job();
  table1["ensemble"]["actuator_scale"] = {{"uniform", {0.8, 1.0}}};
  std::vector<FieldError> errs = ensemble_errors(table1);
  ASSERT_EQ(errs.size(), 1u);
  EXPECT_EQ(errs[0].path, "/ensemble/actuator_scale");
  EXPECT_NE(errs[0].message.find("the spacecraft plant does not declare actuator_scale"),
            std::string::npos)
      << errs[0].message;
  sat["ensemble"]["actuator_misalignment"] = {{"uniform", {0.0, 3.5}}};
  errs = ensemble_errors(sat);
  ASSERT_EQ(errs.size(), 1u);
  EXPECT_EQ(errs[0].path, "/ensemble/actuator_misalignment");
  EXPECT_NE(errs[0].message.find("a member drawing 3.5 would have /actuator_misalignment/0"),
            std::string::npos)
      << errs[0].message;
  sat["ensemble"].erase("actuator_misalignment");
  sat["ensemble"]["actuator_scale"] = {{"uniform", {0.0, 1.0}}};
  errs = ensemble_errors(sat);
  ASSERT_EQ(errs.size(), 1u);
  EXPECT_EQ(errs[0].path, "/ensemble/actuator_scale/uniform/0");
}
