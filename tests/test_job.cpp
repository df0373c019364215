#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <nlohmann/json.hpp>
#include <span>
#include <sstream>

#include "cli_runner.hpp"
#include "ftc/tune/job/job.hpp"
#include "ftc/tune/problem/problem.hpp"
#include "short_job.hpp"

using nlohmann::json;
using namespace ftc;

namespace {

json table1() {
  std::ifstream in(std::string(FTC_SOURCE_DIR) + "/jobs/table1.json");
  return json::parse(in);
}

struct BadCase {
  const char* what;
  std::function<void(json&)> mutate;
  const char* path;
  const char* message;  // substring of the error message
};

// Returns every error of parsing `j`.
std::vector<FieldError> errors_of(const json& j) {
  try {
    tune::parse_job(j, "job.json");
  } catch (const InputError& e) {
    return e.errors();
  }
  return {};
}

// Each case, applied to Table 1, gives an error at its path whose message holds its text.
void expect_each_case_refused(const std::vector<BadCase>& cases) {
  for (const BadCase& c : cases) {
    json k = table1();
    c.mutate(k);
    std::string all;
    bool found = false;
    for (const FieldError& e : errors_of(k)) {
      found = found || (e.path == c.path && e.message.find(c.message) != std::string::npos);
      all += "\n  " + to_string(e);
    }
    EXPECT_TRUE(found) << c.what << ": expected " << c.path << " ~ " << c.message << ", got" << all;
  }
}

}  // namespace

TEST(JobLoader, LoadsTable1WithPaperDefaults) {
  const tune::Job job = tune::load_job(std::string(FTC_SOURCE_DIR) + "/jobs/table1.json");
  EXPECT_EQ(job.name, "table1");
  ASSERT_EQ(job.scenarios.size(), 1u);
  const sim::Scenario& s = job.scenarios[0];
  EXPECT_EQ(s.samples(), 30000);
  EXPECT_EQ(s.faults.size(), 2u);
  EXPECT_EQ(s.faults[1].type, sim::FaultType::loss_of_effectiveness);
  EXPECT_EQ(job.controller.type, sim::ControllerType::pi_fosmc);
  EXPECT_DOUBLE_EQ(job.controller.resolved_alpha1(), 9.0 / 23.0);
  ASSERT_EQ(job.compare.size(), 2u);
  EXPECT_EQ(job.compare[0].label, "NFTSMC");
  EXPECT_EQ(job.compare[0].controller.p, 9.0);
  ASSERT_TRUE(job.tuning.has_value());
  EXPECT_EQ(job.tuning->algorithm->evaluations(), 110);
  EXPECT_EQ(job.tuning->parameters[0].name, "Kp");
  EXPECT_EQ(job.tuning->parameters[1].upper, 50.0);
  EXPECT_EQ(job.steps_per_evaluation(), 30000);
  // Its two faults make each step dearer: 30 000 × (1 + 2/32).
  EXPECT_EQ(job.step_cost_per_evaluation(), 30000 * (1 + 2 * tune::kFaultStepCost));
}

// The step cost counts every scenario's faults, and an ensemble member's largest fault count:
// the short robust-faults job is one listed 10 s scenario with 2 faults and 6 members of 1 or 2.
TEST(JobLoader, StepCostPricesEachScenariosFaults) {
  tune::Job job = tune::parse_job(ftc::testing::short_ensemble_job(), "ensemble");
  EXPECT_EQ(job.steps_per_evaluation(), 7 * 10000);
  EXPECT_EQ(job.step_cost_per_evaluation(), 7 * 10000 * (1 + 2.0 / 32));
  json j = ftc::testing::short_table1_job();
  j["scenarios"][0]["faults"] = json::array();
  job = tune::parse_job(j, "no faults");
  EXPECT_EQ(job.step_cost_per_evaluation(), static_cast<double>(job.steps_per_evaluation()));
}

TEST(JobLoader, FillsDefaultsForOmittedKeys) {
  const json j = {{"schema", "ftctune.job/1"},
                  {"name", "minimal"},
                  {"scenarios", {{{"name", "s"}, {"duration", 2}}}},
                  {"controller", {{"type", "fosmc"}}}};
  const tune::Job job = tune::parse_job(j, "minimal");
  EXPECT_EQ(job.scenarios[0].sample_time, 1e-3);
  EXPECT_EQ(job.scenarios[0].substeps, 1);
  EXPECT_EQ(job.plant.model, "spacecraft");
  EXPECT_EQ(job.plant.values, (std::vector<double>{20.0, 17.0, 15.0, 1.1e-3}));
  EXPECT_EQ(job.controller.c2, 9.0);
  EXPECT_EQ(job.objective.metric->name, "ise");
  EXPECT_FALSE(job.tuning.has_value());
}

TEST(JobLoader, CanonicalJsonRoundTrips) {
  const tune::Job job = tune::parse_job(table1(), "table1");
  const json once = tune::to_json(job);
  const json twice = tune::to_json(tune::parse_job(once, "resolved"));
  EXPECT_EQ(once.dump(), twice.dump());
  EXPECT_EQ(once["controller"]["alpha1"].get<double>(), 0.5625 / (2 - 0.5625));
}

TEST(JobLoader, RejectsBadInputWithJsonPath) {
  const std::vector<BadCase> cases = {
      {"unknown top-level key", [](json& j) { j["colour"] = "red"; }, "/colour", "unknown key"},
      {"unknown scenario key", [](json& j) { j["scenarios"][0]["durration"] = 3; },
       "/scenarios/0/durration", "unknown key"},
      {"wrong type", [](json& j) { j["scenarios"][0]["duration"] = "30"; }, "/scenarios/0/duration",
       "expected a number, got a string"},
      {"negative sample time", [](json& j) { j["scenarios"][0]["sample_time"] = -0.001; },
       "/scenarios/0/sample_time", "must be > 0"},
      {"duration not a multiple of Ts", [](json& j) { j["scenarios"][0]["sample_time"] = 0.007; },
       "/scenarios/0/duration", "whole multiple of sample_time"},
      {"p even", [](json& j) { j["compare"][0]["p"] = 8; }, "/compare/0/p", "positive odd integer"},
      {"p/q outside (1,2)", [](json& j) { j["compare"][0]["p"] = 15; }, "/compare/0/p",
       "p/q must be in (1, 2)"},
      {"alpha not above p/q", [](json& j) { j["compare"][0]["alpha"] = 1.2; }, "/compare/0/alpha",
       "greater than p/q"},
      {"alpha2 = 1", [](json& j) { j["controller"]["alpha2"] = 1; }, "/controller/alpha2",
       "open interval (0, 1)"},
      {"Kp = 0", [](json& j) { j["controller"]["Kp"] = 0; }, "/controller/Kp", "must be > 0"},
      {"actuator 5", [](json& j) { j["scenarios"][0]["faults"][0]["actuator"] = 5; },
       "/scenarios/0/faults/0/actuator", "1..4"},
      {"bounds reversed",
       [](json& j) {
         j["tuning"]["parameters"]["Kp"] = {60, 50};
       },
       "/tuning/parameters/Kp", "lower bound 60 is above upper bound 50"},
      {"unknown tuned parameter",
       [](json& j) {
         j["tuning"]["parameters"]["Kd"] = {0, 1};
       },
       "/tuning/parameters/Kd", "is not a parameter of controller pi_fosmc"},
      {"bound outside field range",
       [](json& j) {
         j["tuning"]["parameters"]["Kp"] = {-1, 50};
       },
       "/tuning/parameters/Kp/0", "outside the valid range of Kp"},
      {"wrong schema", [](json& j) { j["schema"] = "ftctune.job/2"; }, "/schema", "ftctune.job/1"},
      {"field of another controller type", [](json& j) { j["controller"]["sigma1"] = 3; },
       "/controller/sigma1", "does not apply to controller type pi_fosmc"},
      {"unknown controller type", [](json& j) { j["controller"]["type"] = "pid"; },
       "/controller/type", "unknown controller type"},
      {"fraction above 1", [](json& j) { j["scenarios"][0]["faults"][1]["fraction"] = 1.5; },
       "/scenarios/0/faults/1/fraction", "[0, 1]"},
      {"key of another fault type",
       [](json& j) { j["scenarios"][0]["faults"][0]["fraction"] = 0.5; },
       "/scenarios/0/faults/0/fraction", "unknown key"},
      {"window past the end",
       [](json& j) {
         j["objective"]["window"] = {0, 40};
       },
       "/objective/window/1", "after the end of scenario"},
      {"population 0", [](json& j) { j["tuning"]["algorithm"]["population"] = 0; },
       "/tuning/algorithm/population", "1.."},
      {"missing scenarios", [](json& j) { j.erase("scenarios"); }, "/scenarios", "is required"},
      {"short initial state",
       [](json& j) {
         j["scenarios"][0]["initial_state"] = {1, 2, 3, 4, 5};
       },
       "/scenarios/0/initial_state", "expected 6 numbers (X1 and X2 of the plant's 3 axes), got 5"},
      {"incipient without rate",
       [](json& j) {
         j["scenarios"][0]["faults"][0]["profile"] = {{"type", "incipient"}};
       },
       "/scenarios/0/faults/0/profile/rate", "is required"},
      {"unsafe name", [](json& j) { j["name"] = "../x"; }, "/name", "letters, digits"},
      {"substeps 0", [](json& j) { j["scenarios"][0]["substeps"] = 0; }, "/scenarios/0/substeps",
       "1..1000"},
      {"fractional integer", [](json& j) { j["scenarios"][0]["substeps"] = 1.5; },
       "/scenarios/0/substeps", "expected an integer"},
      {"negative seed", [](json& j) { j["tuning"]["seed"] = -3; }, "/tuning/seed",
       "non-negative integer"},
      {"integer parameter tuned",
       [](json& j) {
         j["controller"] = {{"type", "adaptive_neural_pi_fosmc"}};
         j["tuning"]["parameters"] = {{"nodes", {1, 9}}};
       },
       "/tuning/parameters/nodes", "cannot be tuned"},
      {"loudness above 1", [](json& j) { j["tuning"]["algorithm"]["loudness"] = 1.5; },
       "/tuning/algorithm/loudness", "(0, 1]"},
      {"disturbance shape",
       [](json& j) { j["scenarios"][0]["disturbance"][0]["shape"] = "square"; },
       "/scenarios/0/disturbance/0/shape", "\"sin\" or \"cos\""},
  };
  for (const BadCase& c : cases) {
    json j = table1();
    c.mutate(j);
    const std::vector<FieldError> errs = errors_of(j);
    ASSERT_FALSE(errs.empty()) << c.what << ": accepted";
    bool found = false;
    for (const FieldError& e : errs)
      found = found || (e.path == c.path && e.message.find(c.message) != std::string::npos);
    std::string all;
    for (const FieldError& e : errs) all += "\n  " + to_string(e);
    EXPECT_TRUE(found) << c.what << ": expected " << c.path << " ~ " << c.message << ", got" << all;
  }
}

TEST(JobLoader, ReportsEveryErrorAtOnce) {
  json j = table1();
  j["controller"]["Kp"] = -1;
  j["scenarios"][0]["sample_time"] = 0;
  j["extra"] = true;
  try {
    tune::parse_job(j, "job.json");
    FAIL() << "accepted";
  } catch (const InputError& e) {
    EXPECT_EQ(e.errors().size(), 3u);
    EXPECT_NE(std::string(e.what()).find("job.json: "), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("(and 2 more)"), std::string::npos);
  }
}

TEST(JobLoader, SyntaxErrorNamesLine) {
  try {
    tune::parse_job_text("{\n  \"schema\": \"ftctune.job/1\",\n  \"name\": \n}", "broken.json");
    FAIL() << "accepted";
  } catch (const InputError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("broken.json: invalid JSON"), std::string::npos) << what;
    EXPECT_NE(what.find("line 4"), std::string::npos) << what;
  }
}

// The one error of parsing `text` as a job (its path and message); fails when it is accepted.
FieldError only_error(const std::string& text) {
  try {
    tune::parse_job_text(text, "job.json");
  } catch (const InputError& e) {
    EXPECT_EQ(e.errors().size(), 1u) << e.what();
    return e.errors().front();
  }
  ADD_FAILURE() << "accepted: " << text;
  return {};
}

TEST(JobLoader, NumberOutOfRangeIsAnInputErrorNamingItsPath) {
  json j = table1();
  j["controller"]["Kp"] = "HERE";
  std::string text = j.dump(2);
  text.replace(text.find("\"HERE\""), 6, "1e400");
  FieldError e = only_error(text);
  EXPECT_EQ(e.path, "/controller/Kp");
  EXPECT_NE(e.message.find("number 1e400 is out of the range of a double"), std::string::npos)
      << e.message;
  e = only_error(R"({"scenarios": [{"duration": 1}, {"duration": -1e999}]})");
  EXPECT_EQ(e.path, "/scenarios/1/duration");
  e = only_error(R"({"a": [[1, 2], [3, 1E+400]]})");
  EXPECT_EQ(e.path, "/a/1/1");
  EXPECT_EQ(only_error("1e400").path, "");
}

TEST(JobLoader, DuplicateKeysAreRejectedWithTheirPath) {
  FieldError e = only_error(R"({"name": "a", "schema": "ftctune.job/1", "name": "b"})");
  EXPECT_EQ(e.path, "/name");
  EXPECT_NE(e.message.find("duplicate key"), std::string::npos) << e.message;
  e = only_error(
      R"({"controller": {"Kp": 1}, "scenarios": [{}, {"faults": [{"a/b": 1, "a/b": 2}]}]})");
  EXPECT_EQ(e.path, "/scenarios/1/faults/0/a~1b");
}

TEST(JobLoader, TextThatIsNotUtf8IsRejectedWithoutQuotingIt) {
  for (const std::string& text :
       {std::string("{\"name\": \"a\xff\"}"), std::string("{\"name\": \"\xc3\"}"),
        std::string("{\n \xe9 }"), std::string("{\"name\": \"\xed\xa0\x80\"}")}) {
    const FieldError e = only_error(text);
    EXPECT_NE(e.message.find("invalid JSON: not UTF-8"), std::string::npos) << e.message;
    for (char c : e.message) EXPECT_LT(static_cast<unsigned char>(c), 0x80) << e.message;
  }
  EXPECT_NE(only_error("{\n \xe9 }").message.find("line 2, column 2"), std::string::npos);
  // Well-formed UTF-8 is fine.
  try {
    tune::parse_job_text("{\"name\": \"\xc3\xa9\xf0\x9f\x9b\xb0\"}", "job.json");
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()).find("UTF-8"), std::string::npos) << e.what();
  }
}

TEST(JobLoader, DeepNestingIsAnInputError) {
  const FieldError e = only_error(std::string(100000, '[') + std::string(100000, ']'));
  EXPECT_NE(e.message.find("nested deeper than 256 levels"), std::string::npos) << e.message;
}

TEST(JobLoader, ScenariosFileIsReadAsStrictly) {
  const std::filesystem::path dir = ftc::testing::fresh_dir("scenarios-file");
  {
    std::ofstream f(dir / "members.json");
    f << R"({"schema": "ftctune.scenarios/1", "scenarios": [{"duration": 1, "duration": 2}]})";
  }
  json j = table1();
  j["scenarios"] = {{"file", "members.json"}};
  {
    std::ofstream f(dir / "job.json");
    f << j.dump();
  }
  try {
    tune::load_job(dir / "job.json");
    ADD_FAILURE() << "accepted";
  } catch (const InputError& e) {
    ASSERT_FALSE(e.errors().empty());
    EXPECT_EQ(e.errors().front().path, "/scenarios/file");
    EXPECT_NE(e.errors().front().message.find("/scenarios/0/duration: duplicate key"),
              std::string::npos)
        << e.what();
  }
}

// The file's entries are read as the file is parsed, one at a time; what they hold counts only
// once the file proves to be a scenarios file, as if the whole file were read before them.
TEST(JobLoader, ScenariosFileEntriesAreJudgedOnlyInAScenariosFile) {
  const std::filesystem::path dir = ftc::testing::fresh_dir("scenarios-file-entries");
  json j = table1();
  const json good = j["scenarios"][0];
  j["scenarios"] = {{"file", "members.json"}};
  std::ofstream(dir / "job.json") << j.dump();
  json bad = good;
  bad["name"] = "second";
  bad["duration"] = -1;
  const auto errors_with = [&](const std::string& text) {
    std::ofstream(dir / "members.json") << text;
    try {
      tune::load_job(dir / "job.json");
    } catch (const InputError& e) {
      return e.errors();
    }
    return std::vector<FieldError>{};
  };
  // The schema comes after the entries, as `ftctune ensemble` writes it (keys sorted).
  const std::string entries = json::array({good, bad}).dump();
  std::vector<FieldError> errs =
      errors_with(R"({"scenarios": )" + entries + R"(, "schema": "ftctune.scenarios/1"})");
  ASSERT_FALSE(errs.empty());
  EXPECT_EQ(errs.front().path, "/scenarios/1/duration") << errs.front().message;
  // Among the job's own errors, in the place of the job's scenarios: after the plant's, before
  // the controller's, as when the entries were read with the job.
  json also_bad = j;
  also_bad["controller"]["Kp"] = "high";
  also_bad["plant"]["inertia"] = "heavy";
  std::ofstream(dir / "job.json") << also_bad.dump();
  json unread = bad;
  unread["duration"] = "long";  // an error of reading, as the plant's and the controller's
  errs = errors_with(R"({"scenarios": )" + json::array({good, unread}).dump() +
                     R"(, "schema": "ftctune.scenarios/1"})");
  std::vector<std::string> paths;
  for (const FieldError& e : errs) paths.push_back(e.path);
  ASSERT_GE(paths.size(), 3u) << ::testing::PrintToString(paths);
  EXPECT_EQ(paths[0], "/plant/inertia");
  EXPECT_EQ(paths[1], "/scenarios/1/duration");
  EXPECT_EQ(paths[2], "/controller/Kp");
  std::ofstream(dir / "job.json") << j.dump();
  errs = errors_with(R"({"scenarios": )" + entries + R"(, "schema": "ftctune.job/1"})");
  ASSERT_EQ(errs.size(), 1u) << (errs.size() > 1 ? ftc::to_string(errs[1]) : std::string());
  EXPECT_EQ(errs[0].path, "/scenarios/file");
  EXPECT_NE(errs[0].message.find("not a scenarios file"), std::string::npos) << errs[0].message;
  errs = errors_with(R"({"schema": "ftctune.scenarios/1", "scenarios": )" + entries + ", ");
  ASSERT_EQ(errs.size(), 1u) << (errs.size() > 1 ? ftc::to_string(errs[1]) : std::string());
  EXPECT_EQ(errs[0].path, "/scenarios/file");
  EXPECT_NE(errs[0].message.find("invalid JSON"), std::string::npos) << errs[0].message;
  json flagged = good;
  flagged["recoverable"] = 1;
  errs = errors_with(
      json{{"schema", "ftctune.scenarios/1"}, {"scenarios", json::array({flagged})}}.dump());
  ASSERT_EQ(errs.size(), 1u) << (errs.size() > 1 ? ftc::to_string(errs[1]) : std::string());
  EXPECT_NE(errs[0].message.find("/scenarios/0/recoverable must be true or false"),
            std::string::npos)
      << errs[0].message;
  // A good file loads the scenarios the inline job lists.
  bad["duration"] = 40;
  std::ofstream(dir / "members.json")
      << json{{"schema", "ftctune.scenarios/1"}, {"scenarios", {good, bad}}}.dump();
  json inline_job = table1();
  inline_job["scenarios"] = {good, bad};
  EXPECT_EQ(tune::to_json(tune::load_job(dir / "job.json")).dump(),
            tune::to_json(tune::parse_job(inline_job, "inline")).dump());
  // What is not a file to read is an error of the job's field.
  std::filesystem::remove(dir / "members.json");
  std::filesystem::create_directory(dir / "members.json");
  errs = errors_with("");
  ASSERT_EQ(errs.size(), 1u) << (errs.size() > 1 ? ftc::to_string(errs[1]) : std::string());
  EXPECT_EQ(errs[0].path, "/scenarios/file");
  EXPECT_NE(errs[0].message.find("is a directory, not a file to read"), std::string::npos)
      << errs[0].message;
}

TEST(JobLoader, MissingFileIsInputError) {
  EXPECT_THROW(tune::load_job("/nonexistent/job.json"), InputError);
}

TEST(Objective, QuantileAndCvarHandleTiesAndInfinity) {
  tune::ObjectiveConfig o;
  const double inf = std::numeric_limits<double>::infinity();
  o.aggregate = tune::Aggregate::quantile;
  o.q = 0.5;  // nearest rank: v_ceil(0.5 · 5) = v_3
  EXPECT_EQ(o.aggregate_of({3, 1, 2, 2, 5}), 2.0);
  o.q = 0.9;  // v_ceil(4.5) = v_5
  EXPECT_EQ(o.aggregate_of({3, 1, 2, 2, 5}), 5.0);
  o.q = 0.8;  // v_4 with a tie at the top
  EXPECT_EQ(o.aggregate_of({4, 1, 4, 2, 4}), 4.0);
  o.q = 0.1;  // v_1: a quantile below the diverged run is finite
  EXPECT_EQ(o.aggregate_of({inf, 1, 2}), 1.0);
  o.q = 1.0;
  EXPECT_EQ(o.aggregate_of({inf, 1, 2}), inf);
  o.aggregate = tune::Aggregate::cvar;
  o.alpha = 0.5;  // mean of the ceil(0.5 · 5) = 3 largest: (3 + 4 + 4) / 3
  EXPECT_EQ(o.aggregate_of({4, 1, 3, 2, 4}), 11.0 / 3.0);
  o.alpha = 0.9;  // ceil(0.1 · 5) = 1: the largest
  EXPECT_EQ(o.aggregate_of({4, 1, 3, 2, 4}), 4.0);
  o.alpha = 0.0;  // all of them: the mean
  EXPECT_EQ(o.aggregate_of({4, 1, 3, 2, 4}), 14.0 / 5.0);
  o.alpha = 0.5;
  EXPECT_EQ(o.aggregate_of({inf, 1, 2, 3}), inf);  // a diverged run in the tail
  EXPECT_EQ(o.aggregate_of({}), 0.0);
}

TEST(Objective, WindowFromFirstFaultShiftsAndCutsEachScenariosWindow) {
  tune::ObjectiveConfig o;
  o.window = {0, 8};
  o.window_from = tune::WindowFrom::first_fault;
  sim::Scenario s;
  s.duration = 12;
  sim::Fault a, b;
  a.onset = 7;
  b.onset = 5.5;
  s.faults = {a, b};
  EXPECT_EQ(o.window_of(s).t0, 5.5);  // the earliest onset, whatever the order
  EXPECT_EQ(o.window_of(s).t1, 12);   // 13.5 is past the end
  s.faults.clear();                   // no fault: measured from the start
  EXPECT_EQ(o.window_of(s).t0, 0);
  EXPECT_EQ(o.window_of(s).t1, 8);
}

TEST(JobLoader, LogScaleBoundsMustBePositiveAndInsideTheFieldsRange) {
  json j = table1();
  j["tuning"]["parameters"]["Kp"] = {{"bounds", {0, 50}}, {"scale", "log"}};
  std::vector<FieldError> errs = errors_of(j);
  ASSERT_FALSE(errs.empty());
  EXPECT_EQ(errs[0].path, "/tuning/parameters/Kp/bounds/0") << to_string(errs[0]);
  j["tuning"]["parameters"]["Kp"] = {{"bounds", {1, 50}}, {"scale", "cubic"}};
  errs = errors_of(j);
  ASSERT_FALSE(errs.empty());
  EXPECT_EQ(errs[0].path, "/tuning/parameters/Kp/scale") << to_string(errs[0]);
  // alpha2 must stay in (0, 1) whatever the tuning bounds say.
  j["tuning"]["parameters"] = {{"alpha2", {{"bounds", {0.4, 1.2}}, {"scale", "log"}}}};
  errs = errors_of(j);
  ASSERT_EQ(errs.size(), 1u);
  EXPECT_EQ(errs[0].path, "/tuning/parameters/alpha2/bounds/1") << to_string(errs[0]);
  EXPECT_NE(errs[0].message.find("outside the valid range of alpha2"), std::string::npos);
}

// A near miss of an enumeration's value, or a key with two letters swapped, is named.
TEST(JobLoader, SuggestsTheNearestEnumValueAndSwappedLetters) {
  const auto first = [](const json& j) {
    const std::vector<FieldError> errs = errors_of(j);
    return errs.empty() ? FieldError{} : errs[0];
  };
  json j = table1();
  j["controller"]["type"] = "pi-fosmc";
  FieldError e = first(j);
  EXPECT_EQ(e.path, "/controller/type") << to_string(e);
  EXPECT_NE(e.message.find("did you mean \"pi_fosmc\"?"), std::string::npos) << e.message;
  j = table1();
  j["objective"]["metric"] = "ies";
  e = first(j);
  EXPECT_EQ(e.path, "/objective/metric") << to_string(e);
  EXPECT_NE(e.message.find("(got \"ies\"); did you mean \"ise\"?"), std::string::npos) << e.message;
  j = table1();
  j["objective"]["aggregate"] = "cavr";
  EXPECT_NE(first(j).message.find("did you mean \"cvar\"?"), std::string::npos);
  j = table1();
  j["scenarios"][0]["faults"][0]["onest"] = j["scenarios"][0]["faults"][0]["onset"];
  j["scenarios"][0]["faults"][0].erase("onset");
  bool suggested = false;  // beside "onset is required"
  for (const FieldError& f : errors_of(j))
    suggested = suggested || (f.path == "/scenarios/0/faults/0/onest" &&
                              f.message.find("did you mean \"onset\"?") != std::string::npos);
  EXPECT_TRUE(suggested);
  // Far from every value: no guess.
  j = table1();
  j["objective"]["metric"] = "energy";
  EXPECT_EQ(first(j).message.find("did you mean"), std::string::npos) << first(j).message;
}

// Model mismatch and ensemble scales address the parameters a plant declares uncertain, and a
// fault the actuators it has: a job that is fine for one plant is exit 2 for another, naming the
// JSON path (through the CLI, as a user meets it).
TEST(JobLoader, UncertainParametersAndActuatorsAreThePlantsOwn) {
  const auto dir = ftc::testing::fresh_dir("uncertain");
  const auto read = [](const std::string& name) {
    std::ifstream in(std::string(FTC_SOURCE_DIR) + "/jobs/" + name);
    return json::parse(in);
  };
  const auto validate = [&](const json& j) {
    const auto file = dir / "job.json";
    std::ofstream(file) << j.dump(2);
    return ftc::testing::run_cli("validate '" + file.string() + "'", dir);
  };
  const auto expect_error = [&](const json& j, const std::string& path, const std::string& what) {
    const ftc::testing::CliResult r = validate(j);
    EXPECT_EQ(r.exit_code, 2) << r.err;
    EXPECT_NE(r.err.find(path + ": "), std::string::npos) << r.err;
    EXPECT_NE(r.err.find(what), std::string::npos) << r.err;
  };

  // The arm declares no uncertain parameters: neither a true inertia nor a scale of one.
  json arm = read("manipulator.json");
  arm["scenarios"][0]["inertia"] = {0.1, 0.1};
  expect_error(arm, "/scenarios/0/inertia",
               "the manipulator plant does not declare inertia uncertain (its uncertain "
               "parameters: none)");
  EXPECT_EQ(errors_of(arm).size(), 1u);
  arm = read("manipulator.json");
  arm["ensemble"] = {{"count", 4}, {"seed", 1}, {"inertia_scale", {{"uniform", {0.8, 1.2}}}}};
  expect_error(arm, "/ensemble/inertia_scale",
               "the manipulator plant declares no uncertain parameters to scale");

  // The hexarotor has 6 rotors, and declares its inertia uncertain.
  json hex = read("hexarotor.json");
  hex["scenarios"][0]["faults"][0]["actuator"] = 7;
  expect_error(hex, "/scenarios/0/faults/0/actuator", "1..6");
  hex = read("hexarotor.json");
  hex["scenarios"][0]["inertia"] = {0.012, 0.015};
  expect_error(hex, "/scenarios/0/inertia", "expected 3 numbers (the hexarotor's inertia), got 2");
  hex["scenarios"][0]["inertia"] = {0.012, -0.015, 0.021};
  expect_error(hex, "/scenarios/0/inertia/1", "must be > 0");
  hex["scenarios"][0]["inertia"] = {0.012, 0.015, 0.021};
  hex["ensemble"] = {{"count", 4}, {"seed", 1}, {"inertia_scale", {{"uniform", {0.8, 1.2}}}}};
  const ftc::testing::CliResult ok = validate(hex);
  EXPECT_EQ(ok.exit_code, 0) << ok.err;
}

TEST(JobLoader, MetricsBlockGivesTheSettlingThresholdAndTailAtTheirPaths) {
  // Without the block the resolved job has no "metrics" (a job keeps its canonical form and
  // hash) and the simulations no threshold or tail.
  json j = table1();
  const tune::Job plain = tune::parse_job(j, "t");
  EXPECT_FALSE(tune::to_json(plain).contains("metrics"));
  const sim::SimulationOptions none = tune::TuningProblem(plain).simulation_options(0, 0);
  EXPECT_TRUE(std::isnan(none.metrics.settling_threshold));
  EXPECT_TRUE(std::isnan(none.metrics.steady_state_tail));
  // With it, both reach every simulation's options, and the block round-trips.
  j["metrics"] = {{"settling_threshold", 0.01}, {"steady_state_tail", 5}};
  const tune::Job job = tune::parse_job(j, "t");
  EXPECT_EQ(tune::to_json(job)["metrics"], j["metrics"]);
  const sim::SimulationOptions o = tune::TuningProblem(job).simulation_options(0, 0);
  EXPECT_EQ(o.metrics.settling_threshold, 0.01);
  EXPECT_EQ(o.metrics.steady_state_tail, 5.0);
  j["metrics"] = {{"steady_state_tail", 2}};  // one without the other
  EXPECT_TRUE(std::isnan(tune::TuningProblem(tune::parse_job(j, "t"))
                             .simulation_options(0, 0)
                             .metrics.settling_threshold));
  const std::vector<BadCase> cases = {
      {"threshold 0",
       [](json& k) {
         k["metrics"] = {{"settling_threshold", 0}};
       },
       "/metrics/settling_threshold", "> 0"},
      {"negative tail",
       [](json& k) {
         k["metrics"] = {{"steady_state_tail", -1}};
       },
       "/metrics/steady_state_tail", "> 0"},
      {"unknown key",
       [](json& k) {
         k["metrics"] = {{"threshold", 0.1}};
       },
       "/metrics/threshold", "unknown key"},
      {"not a number",
       [](json& k) {
         k["metrics"] = {{"steady_state_tail", "5"}};
       },
       "/metrics/steady_state_tail", "expected a number"},
  };
  expect_each_case_refused(cases);
}

namespace {

// table1 with its objective replaced by these goals.
json with_goals(json goals) {
  json j = table1();
  j.erase("objective");
  j["goals"] = std::move(goals);
  return j;
}

json soft_ise() { return {{"metric", "ise"}, {"window", {10, 30}}, {"minimize", true}}; }

}  // namespace

TEST(JobGoals, ParseWriteBackCanonicallyAndGiveTheObjective) {
  const json goals = json::array(
      {soft_ise(),
       {{"metric", "control_tv"}, {"aggregate", "cvar"}, {"alpha", 0.8}, {"at_most", 4000}},
       {{"metric", "peak_command"}, {"aggregate", "max"}, {"at_most", 17.9}},
       {{"metric", "settling_time"},
        {"window_from", "first_fault"},
        {"window", {0, 10}},
        {"threshold", 0.05},
        {"at_most", 5}}});
  const tune::Job job = tune::parse_job(with_goals(goals), "t");
  ASSERT_EQ(job.goals.size(), 4u);
  EXPECT_TRUE(job.goals[0].soft());
  EXPECT_EQ(job.goals[1].metric, &sim::kMetricFields[sim::metric_index("control_tv")]);
  EXPECT_EQ(job.goals[1].aggregate, tune::Aggregate::cvar);
  EXPECT_EQ(job.goals[1].alpha, 0.8);
  EXPECT_EQ(job.goals[2].at_most, 17.9);
  EXPECT_EQ(job.goals[3].window_from, tune::WindowFrom::first_fault);
  // The soft goal on ise is the objective the runs score by.
  EXPECT_EQ(job.objective.metric, job.goals[0].metric);
  EXPECT_EQ(job.objective.metric->name, "ise");
  EXPECT_EQ(job.objective.window.t0, 10.0);
  EXPECT_EQ(job.objective.window.t1, 30.0);
  // Written back with every default filled in, without an objective, and stable.
  const json once = tune::to_json(job);
  EXPECT_FALSE(once.contains("objective"));
  EXPECT_EQ(
      once["goals"][0],
      json({{"aggregate", "mean"}, {"metric", "ise"}, {"minimize", true}, {"window", {10, 30}}}));
  EXPECT_EQ(once["goals"][1], json({{"aggregate", "cvar"},
                                    {"alpha", 0.8},
                                    {"at_most", 4000},
                                    {"metric", "control_tv"},
                                    {"window", {0, nullptr}}}));
  EXPECT_EQ(once.dump(), tune::to_json(tune::parse_job(once, "resolved")).dump());
  // A job without goals writes none.
  EXPECT_FALSE(tune::to_json(tune::parse_job(table1(), "t")).contains("goals"));
  // The normalised violation of a hard goal.
  EXPECT_EQ(job.goals[2].violation(17.9), 0.0);
  EXPECT_EQ(job.goals[2].violation(10.0), 0.0);
  EXPECT_DOUBLE_EQ(job.goals[2].violation(2 * 17.9), 1.0);
  EXPECT_EQ(job.goals[2].violation(std::numeric_limits<double>::infinity()),
            std::numeric_limits<double>::infinity());
  EXPECT_EQ(job.goals[0].violation(1e9), 0.0);  // soft: never violated
}

// tuning.noise_floor (issue 42): "every_point" (the default, left out of the canonical form so
// that jobs written before the key keep their sha256) or "picked"; anything else is refused at
// its path, naming both.
TEST(JobLoader, NoiseFloorOfAFrontIsEveryPointOrThePickedOne) {
  json j = table1();
  EXPECT_EQ(tune::parse_job(j, "t").tuning->noise_floor, tune::FrontNoiseFloor::every_point);
  EXPECT_FALSE(tune::to_json(tune::parse_job(j, "t"))["tuning"].contains("noise_floor"));
  j["tuning"]["noise_floor"] = "every_point";
  EXPECT_FALSE(tune::to_json(tune::parse_job(j, "t"))["tuning"].contains("noise_floor"));
  j["tuning"]["noise_floor"] = "picked";
  const tune::Job picked = tune::parse_job(j, "t");
  EXPECT_EQ(picked.tuning->noise_floor, tune::FrontNoiseFloor::picked);
  EXPECT_EQ(tune::to_json(picked)["tuning"]["noise_floor"], "picked");
  EXPECT_EQ(tune::to_json(tune::parse_job(tune::to_json(picked), "again")).dump(),
            tune::to_json(picked).dump());
  j["tuning"]["noise_floor"] = "knee";
  try {
    tune::parse_job(j, "t");
    FAIL() << "a noise floor of \"knee\" was accepted";
  } catch (const InputError& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("/tuning/noise_floor"), std::string::npos) << m;
    EXPECT_NE(m.find("every_point"), std::string::npos) << m;
    EXPECT_NE(m.find("picked"), std::string::npos) << m;
  }
}

// A scenario's saturation: one number for every actuator, or one per actuator; written back as
// it was given; anything else refused at its path, saying what is accepted.
TEST(JobLoader, SaturationIsOneNumberOrOnePerActuator) {
  const auto has_error = [](const json& j, const std::string& path, const std::string& text) {
    for (const FieldError& e : errors_of(j))
      if (e.path == path && e.message.find(text) != std::string::npos) return true;
    return false;
  };
  json j = table1();
  j["scenarios"][0]["saturation"] = 30;
  tune::Job job = tune::parse_job(j, "one");
  EXPECT_EQ(job.scenarios[0].saturation.values, std::vector<double>{30.0});
  EXPECT_EQ(tune::to_json(job)["scenarios"][0]["saturation"], 30);
  j["scenarios"][0]["saturation"] = {10, 20, 30, 40};
  job = tune::parse_job(j, "each");
  EXPECT_EQ(job.scenarios[0].saturation.limit(2), 30.0);
  EXPECT_EQ(tune::to_json(job)["scenarios"][0]["saturation"], json({10, 20, 30, 40}));
  EXPECT_EQ(tune::to_json(tune::parse_job(tune::to_json(job), "again")), tune::to_json(job));
  j["scenarios"][0]["saturation"] = {10, 20, 30};
  EXPECT_TRUE(has_error(j, "/scenarios/0/saturation", "one per actuator of the plant's 4"));
  j["scenarios"][0]["saturation"] = {10, "x", 30, 40};
  EXPECT_TRUE(has_error(j, "/scenarios/0/saturation/1", "expected a number"));
  j["scenarios"][0]["saturation"] = {10, 0, 30, 40};
  EXPECT_TRUE(has_error(j, "/scenarios/0/saturation/1", "> 0"));
  j["scenarios"][0]["saturation"] = "high";
  EXPECT_TRUE(has_error(j, "/scenarios/0/saturation",
                        "expected a number or an array of numbers (one per actuator)"));
}

// Which metrics a goal and the objective may name, whether a goal takes a window, and which one
// takes a threshold or a tail: each from the metrics record's traits, for every field, and the
// JSON Schema's enums are the table's.
TEST(JobLoader, GoalMetricsAndTheirChecksComeFromTheMetricsRecord) {
  const auto has_error = [](const json& j, const std::string& path, const std::string& text) {
    for (const FieldError& e : errors_of(j))
      if (e.path == path && e.message.find(text) != std::string::npos) return true;
    return false;
  };
  std::vector<std::string> goal_names, objective_names;
  for (const sim::MetricField& f : sim::kMetricFields) {
    const std::string name(f.name);
    if (f.goal) goal_names.push_back(name);
    if (f.objective) objective_names.push_back(name);
    // What the field is measured against, given in the goal.
    json goal = {{"metric", name}, {"at_most", 1}};
    if (f.setting == sim::MetricSetting::settling_threshold) goal["threshold"] = 0.05;
    if (f.setting == sim::MetricSetting::steady_state_tail) goal["tail"] = 2;
    const json limited = with_goals({soft_ise(), goal});
    if (!f.goal) {
      EXPECT_TRUE(has_error(limited, "/goals/1/metric", "must be one of")) << name;
      continue;
    }
    const tune::Job job = tune::parse_job(limited, name);
    EXPECT_EQ(job.goals[1].metric, &f) << name;
    EXPECT_EQ(job.goals[1].windowed(), f.scope == sim::MetricScope::window) << name;
    // A window only for a window field.
    json windowed = goal;
    windowed["window"] = {1, 2};
    const json with_window = with_goals({soft_ise(), windowed});
    if (f.scope == sim::MetricScope::window)
      EXPECT_NO_THROW(tune::parse_job(with_window, name)) << name;
    else
      EXPECT_TRUE(has_error(with_window, "/goals/1/window",
                            name + " is measured over the whole run; it takes no window"))
          << name;
    // A threshold or tail only for the field measured against it.
    for (const auto& [key, setting] :
         {std::pair{"threshold", sim::MetricSetting::settling_threshold},
          std::pair{"tail", sim::MetricSetting::steady_state_tail}}) {
      json extra = goal;
      extra[key] = 1;
      const json j = with_goals({soft_ise(), extra});
      EXPECT_EQ(has_error(j, std::string("/goals/1/") + key, "is used only with metric"),
                f.setting != setting)
          << name << " " << key;
      if (f.setting == setting) {  // and it is needed
        EXPECT_TRUE(has_error(with_goals({soft_ise(), {{"metric", name}, {"at_most", 1}}}),
                              std::string("/goals/1/") + key, name + " needs a " + key))
            << name;
      }
    }
    // One soft goal is the objective: only a field that can be.
    json soft = goal;
    soft.erase("at_most");
    soft["minimize"] = true;
    if (f.objective) {
      EXPECT_EQ(tune::parse_job(with_goals(json::array({soft})), name).objective.metric, &f)
          << name;
    } else {
      EXPECT_TRUE(
          has_error(with_goals(json::array({soft})), "/goals/0/metric",
                    "a single soft goal is the search's objective: ise, iae or itae (got " + name))
          << name;
    }
  }
  for (const sim::MetricField& f : sim::kMetricFields) {
    json j = table1();
    j["objective"]["metric"] = f.name;
    if (f.objective)
      EXPECT_EQ(tune::parse_job(j, "objective").objective.metric, &f) << f.name;
    else
      EXPECT_TRUE(has_error(j, "/objective/metric", "must be \"ise\", \"iae\" or") ||
                  has_error(j, "/objective/metric", "must be one of"))
          << f.name;
  }
  const json schema = tune::job_json_schema();
  EXPECT_EQ(schema["properties"]["goals"]["items"]["properties"]["metric"]["enum"], goal_names);
  EXPECT_EQ(schema["properties"]["objective"]["properties"]["metric"]["enum"], objective_names);
}

TEST(JobGoals, BadGoalsAreRejectedAtTheirPaths) {
  const auto goals = [](json extra) {
    return [extra](json& j) {
      j.erase("objective");
      j["goals"] = json::array({soft_ise()});
      for (const json& g : extra) j["goals"].push_back(g);
    };
  };
  const std::vector<BadCase> cases = {
      {"unknown metric", goals({{{"metric", "chatter"}, {"at_most", 1}}}), "/goals/1/metric",
       "control_tv"},
      {"limit 0", goals({{{"metric", "peak_command"}, {"at_most", 0}}}), "/goals/1/at_most", "> 0"},
      {"negative limit", goals({{{"metric", "ise"}, {"at_most", -2}}}), "/goals/1/at_most", "> 0"},
      {"window after the run", goals({{{"metric", "iae"}, {"window", {0, 40}}, {"at_most", 1}}}),
       "/goals/1/window/1", "after the end of scenario"},
      {"window backwards", goals({{{"metric", "iae"}, {"window", {5, 2}}, {"at_most", 1}}}),
       "/goals/1/window", "must be after start"},
      {"window on a whole-run metric",
       goals({{{"metric", "control_tv"}, {"window", {10, 30}}, {"at_most", 1}}}), "/goals/1/window",
       "whole run"},
      {"duplicate", goals(json::array({soft_ise()})), "/goals/1", "same goal as /goals/0"},
      {"settling without threshold", goals({{{"metric", "settling_time"}, {"at_most", 3}}}),
       "/goals/1/threshold", "needs a threshold"},
      {"steady state without tail", goals({{{"metric", "steady_state_error"}, {"at_most", 3}}}),
       "/goals/1/tail", "needs a tail"},
      {"threshold on another metric",
       goals({{{"metric", "ise"}, {"threshold", 0.1}, {"at_most", 3}}}), "/goals/1/threshold",
       "only with metric \"settling_time\""},
      {"neither minimize nor at_most", goals({{{"metric", "iae"}}}), "/goals/1", "at_most"},
      {"both", goals({{{"metric", "iae"}, {"minimize", true}, {"at_most", 2}}}), "/goals/1/at_most",
       "not both"},
      {"minimize false", goals({{{"metric", "iae"}, {"minimize", false}}}), "/goals/1/minimize",
       "must be true"},
      {"alpha without cvar", goals({{{"metric", "iae"}, {"alpha", 0.5}, {"at_most", 2}}}),
       "/goals/1/alpha", "only with aggregate"},
      {"unknown aggregate", goals({{{"metric", "iae"}, {"aggregate", "median"}, {"at_most", 2}}}),
       "/goals/1/aggregate", "mean"},
      {"objective and goals", [](json& j) { j["goals"] = json::array({soft_ise()}); }, "/goals",
       "not both"},
      {"empty goals",
       [](json& j) {
         j.erase("objective");
         j["goals"] = json::array();
       },
       "/goals", "at least one goal"},
      {"no soft goal",
       [](json& j) {
         j.erase("objective");
         j["goals"] = json::array({{{"metric", "ise"}, {"at_most", 2}}});
       },
       "/goals", "minimize"},
  };
  expect_each_case_refused(cases);
  // The job's metrics block gives the threshold too; one given in both places must agree.
  json j = with_goals(json::array({soft_ise(), {{"metric", "settling_time"}, {"at_most", 3}}}));
  j["metrics"] = {{"settling_threshold", 0.05}};
  EXPECT_TRUE(errors_of(j).empty());
  j["goals"][1]["threshold"] = 0.1;
  const std::vector<FieldError> errs = errors_of(j);
  ASSERT_EQ(errs.size(), 1u);
  EXPECT_EQ(errs[0].path, "/goals/1/threshold");
}

TEST(JobGoals, ValidationRefusesAFrontTheAlgorithmCannotSearchAndAnObjectiveOfNoErrorIntegral) {
  const auto refusal = [](const json& j) -> std::string {
    const std::vector<FieldError> errs = errors_of(j);
    return errs.empty() ? "" : errs[0].path + " " + errs[0].message;
  };
  // One soft goal on an error integral is the objective: the problem is the objective's.
  EXPECT_EQ(refusal(with_goals(json::array({soft_ise()}))), "");
  // Two soft goals of any metric ask for a front: random search samples one...
  json front = with_goals(json::array({soft_ise(),
                                       {{"metric", "control_tv"}, {"minimize", true}},
                                       {{"metric", "saturation_fraction"}, {"minimize", true}}}));
  front["tuning"]["algorithm"] = {{"type", "random"}, {"population", 4}, {"iterations", 1}};
  EXPECT_EQ(refusal(front), "");
  EXPECT_NO_THROW(tune::TuningProblem(tune::parse_job(front, "t")));
  // ...an algorithm of one objective does not, and `validate` says so at the algorithm.
  front["tuning"]["algorithm"] = {
      {"type", "pagmo"}, {"name", "sade"}, {"population", 7}, {"generations", 2}};
  const std::string pareto = refusal(front);
  EXPECT_NE(pareto.find("/tuning/algorithm/type 3 soft goals"), std::string::npos) << pareto;
  EXPECT_NE(pareto.find("Pareto front"), std::string::npos) << pareto;
  // Hard goals on any metric make a constrained search (TuningRun.HardGoalIsMetByTheWinner...).
  EXPECT_EQ(refusal(with_goals(
                json::array({soft_ise(), {{"metric", "peak_command"}, {"at_most", 17.9}}}))),
            "");
  // A single soft goal is the objective, so it is an error integral; validation says so.
  EXPECT_NE(refusal(with_goals(json::array({{{"metric", "control_energy"}, {"minimize", true}}})))
                .find("/goals/0/metric a single soft goal"),
            std::string::npos);
}

TEST(JobGoals, GoalValuesAreTheMetricsInTheirOwnWindows) {
  // Table 1 (faults at 10 s and 20 s) with goals in windows of their own: each goal's window is
  // simulated, and its value is what a simulation with that window as its main one measures.
  json j = with_goals(json::array(
      {soft_ise(),
       {{"metric", "peak_command"}, {"window", {2, 8}}, {"at_most", 1e9}},
       {{"metric", "steady_state_error"},
        {"window_from", "first_fault"},
        {"window", {0, 5}},
        {"tail", 2},
        {"at_most", 1e9}},
       {{"metric", "peak_error_after_fault"}, {"aggregate", "max"}, {"at_most", 1e-9}}}));
  const tune::TuningProblem problem(tune::parse_job(j, "t"));
  const sim::SimulationOptions o = problem.simulation_options(0);
  const auto has = [&](double t0, double t1) {
    for (const sim::Window& w : o.extra_windows)
      if (w.t0 == t0 && w.t1 == t1) return true;
    return false;
  };
  EXPECT_TRUE(has(2, 8));
  EXPECT_TRUE(has(10, 15));  // from the first fault at 10 s
  EXPECT_EQ(o.metrics.steady_state_tail, 2.0);
  const sim::ControllerConfig c = problem.job().controller;
  tune::SerialEvaluator serial;
  const tune::Evaluation e =
      problem.evaluate(std::span<const sim::ControllerConfig>(&c, 1), serial)[0].evaluation;
  ASSERT_EQ(e.goals.size(), 4u);
  EXPECT_EQ(e.goals[0], e.objective);
  const auto measured = [&](double t0, double t1) {
    sim::SimulationOptions alone;
    alone.window = {t0, t1};
    alone.metrics.steady_state_tail = 2;
    return problem.plant().simulate(c, problem.scenario(0), alone).metrics;
  };
  EXPECT_EQ(e.goals[1], measured(2, 8).errors.peak_command);
  EXPECT_EQ(e.goals[2], measured(10, 15).errors.steady_state_error);
  const sim::Metrics whole = measured(0, 30);
  EXPECT_EQ(e.goals[3], std::max(whole.peak_error_after_fault[0], whole.peak_error_after_fault[1]));
  // Only the last goal is violated, by its value / limit - 1.
  EXPECT_DOUBLE_EQ(e.violation, e.goals[3] / 1e-9 - 1);
  EXPECT_FALSE(e.feasible());
  EXPECT_EQ(e.fitness, tune::constrained_fitness(tune::fitness_of(e.objective), e.violation));
  EXPECT_LT(e.fitness, 0.0);
}

// A candidate whose simulations cannot run (an invalid controller) meets no goal and ranks below
// every candidate that ran; a goal that no counted scenario defines (a settling time on a run
// without faults) is NaN, which no limit accepts, not the aggregate of nothing.
TEST(JobGoals, FailedCandidatesAndUndefinedGoalsMeetNoLimit) {
  json j = with_goals(json::array(
      {soft_ise(), {{"metric", "peak_command"}, {"window", {2, 8}}, {"at_most", 1e9}}}));
  const tune::TuningProblem problem(tune::parse_job(j, "t"));
  sim::ControllerConfig bad = problem.job().controller;
  bad.Kp = std::numeric_limits<double>::quiet_NaN();
  tune::SerialEvaluator serial;
  const tune::CandidateOutcome failed =
      problem.evaluate(std::span<const sim::ControllerConfig>(&bad, 1), serial)[0];
  EXPECT_FALSE(failed.error.empty());
  ASSERT_EQ(failed.evaluation.goals.size(), 2u);
  EXPECT_EQ(failed.evaluation.goals[1], std::numeric_limits<double>::infinity());
  EXPECT_FALSE(failed.evaluation.feasible());
  EXPECT_EQ(failed.evaluation.fitness, -1.0);

  json calm = with_goals(json::array(
      {soft_ise(), {{"metric", "settling_time"}, {"threshold", 0.01}, {"at_most", 5}}}));
  // validate refuses such a job (JobLoader.AGoalMeasuredAfterAFaultNeedsAScenarioWithOne); the
  // problem's rule still holds for runs validation cannot see, so the faults go after it.
  const tune::Job with_faults = tune::parse_job(calm, "t");
  std::vector<sim::Scenario> no_faults = with_faults.scenarios;
  for (sim::Scenario& s : no_faults) s.faults.clear();
  const tune::TuningProblem quiet(with_faults, no_faults, no_faults.size());
  const sim::ControllerConfig c = quiet.job().controller;
  const tune::Evaluation e =
      quiet.evaluate(std::span<const sim::ControllerConfig>(&c, 1), serial)[0].evaluation;
  ASSERT_EQ(e.goals.size(), 2u);
  EXPECT_TRUE(std::isnan(e.goals[1]));
  EXPECT_EQ(e.violation, std::numeric_limits<double>::infinity());
  EXPECT_FALSE(e.feasible());
}

// A run measures one settling threshold and one steady-state tail: two goals asking for
// different ones are refused at the second one's path.
TEST(JobGoals, TwoGoalsMayNotAskForDifferentThresholdsOrTails) {
  json j = with_goals(json::array(
      {soft_ise(),
       {{"metric", "settling_time"}, {"threshold", 0.01}, {"at_most", 5}},
       {{"metric", "settling_time"}, {"threshold", 0.1}, {"aggregate", "max"}, {"at_most", 5}},
       {{"metric", "steady_state_error"}, {"tail", 2}, {"at_most", 1}},
       {{"metric", "steady_state_error"}, {"tail", 3}, {"aggregate", "max"}, {"at_most", 1}}}));
  const std::vector<FieldError> errs = errors_of(j);
  const auto has = [&](const std::string& path, const std::string& text) {
    for (const FieldError& e : errs)
      if (e.path == path && e.message.find(text) != std::string::npos) return true;
    return false;
  };
  EXPECT_TRUE(has("/goals/2/threshold", "differs from /goals/1/threshold 0.01")) << errs.size();
  EXPECT_TRUE(has("/goals/4/tail", "differs from /goals/3/tail 2")) << errs.size();
}

// The scenario's actuator block: absent, a job keeps its canonical form (and hash); present, it
// reaches the scenario and round-trips; bad values are refused at their paths.
TEST(JobLoader, ActuatorBlockParsesRoundTripsAndIsCheckedAtItsPaths) {
  json j = table1();
  const tune::Job plain = tune::parse_job(j, "t");
  EXPECT_FALSE(plain.scenarios[0].actuator.has_value());
  EXPECT_FALSE(tune::to_json(plain)["scenarios"][0].contains("actuator"));
  j["scenarios"][0]["actuator"] = {{"time_constant", 0.02}, {"rate_limit", 50}};
  const tune::Job job = tune::parse_job(j, "t");
  ASSERT_TRUE(job.scenarios[0].actuator.has_value());
  EXPECT_EQ(*job.scenarios[0].actuator->time_constant, 0.02);
  EXPECT_EQ(*job.scenarios[0].actuator->rate_limit, 50.0);
  EXPECT_EQ(tune::to_json(job)["scenarios"][0]["actuator"], j["scenarios"][0]["actuator"]);
  EXPECT_EQ(tune::to_json(tune::scenario_from_json(tune::to_json(job.scenarios[0]), "s")),
            tune::to_json(job.scenarios[0]));  // what rank 0 sends its workers
  j["scenarios"][0]["actuator"] = {{"rate_limit", 50}};
  EXPECT_FALSE(tune::parse_job(j, "t").scenarios[0].actuator->time_constant.has_value());
  const std::vector<BadCase> cases = {
      {"empty", [](json& k) { k["scenarios"][0]["actuator"] = json::object(); },
       "/scenarios/0/actuator", "time_constant, rate_limit or both"},
      {"zero time constant",
       [](json& k) {
         k["scenarios"][0]["actuator"] = {{"time_constant", 0}};
       },
       "/scenarios/0/actuator/time_constant", "> 0"},
      {"time constant under two steps",
       [](json& k) {
         k["scenarios"][0]["actuator"] = {{"time_constant", 0.0015}};
       },
       "/scenarios/0/actuator/time_constant", "at least 2 integration steps"},
      {"negative rate limit",
       [](json& k) {
         k["scenarios"][0]["actuator"] = {{"rate_limit", -1}};
       },
       "/scenarios/0/actuator/rate_limit", "> 0"},
      {"unknown key",
       [](json& k) {
         k["scenarios"][0]["actuator"] = {{"tau", 0.1}};
       },
       "/scenarios/0/actuator/tau", "unknown key"},
  };
  expect_each_case_refused(cases);
}

// A window that holds no sample measures nothing (#44 item 5): `validate` passed it, and `run`
// then searched blind (every candidate 0, J = inf). Samples are at k·Ts, 0 <= k < duration/Ts.
TEST(JobLoader, AWindowThatHoldsNoSampleIsRefused) {
  const auto first = [](const json& j) {
    const std::vector<FieldError> errs = errors_of(j);
    return errs.empty() ? std::string() : to_string(errs[0]);
  };
  json j = table1();  // 30 s at 1 ms, faults at 10 s and 20 s
  j["objective"]["window"] = {30, nullptr};
  EXPECT_EQ(first(j),
            "/objective/window: holds no sample of scenario \"paper\" (samples at k·0.001 s "
            "before its end at 30 s)");
  j["objective"]["window"] = {29.9995, 30};
  EXPECT_NE(first(j).find("/objective/window: holds no sample"), std::string::npos) << first(j);
  j["objective"]["window"] = {29.999, 30};  // the last sample, 29.999 s
  EXPECT_EQ(first(j), "");
  // Counted from the first fault (10 s): 20 s on is the end.
  j["objective"]["window"] = {20, 25};
  j["objective"]["window_from"] = "first_fault";
  EXPECT_EQ(first(j),
            "/objective/window: holds no sample of scenario \"paper\" counted from its first "
            "fault at 10 s (samples at k·0.001 s before its end at 30 s)");
  j["objective"]["window"] = {19.5, 25};
  EXPECT_EQ(first(j), "");
  // A goal's window is checked alike.
  j.erase("objective");
  j["goals"] = {{{"metric", "ise"}, {"window", {31, nullptr}}, {"minimize", true}}};
  EXPECT_NE(first(j).find("/goals/0/window"), std::string::npos) << first(j);
  // Ensemble members whose first fault the draws put at up to 17 s of an 18 s run leave
  // [2, 8) s after it empty: such a member counted 0.
  std::ifstream in(std::string(FTC_SOURCE_DIR) + "/jobs/robust-faults.json");
  json e = json::parse(in);
  e["ensemble"]["faults"]["onset"] = {{"uniform", {5, 17}}};
  e["objective"]["window"] = {2, 8};
  EXPECT_EQ(first(e),
            "/objective/window: holds no sample of an ensemble member whose first fault is at "
            "17 s, the latest ensemble.faults.onset draws (samples at k·0.001 s before its end "
            "at 18 s): shorten the window's start or the onsets");
  e["objective"]["window"] = {0, 8};
  EXPECT_EQ(first(e), "");
}

// A goal measured after a fault (settling_time, peak_error_after_fault) in a job without any:
// every candidate scored NaN, the front was empty, and `run` exited 0 (#44 item 6).
TEST(JobLoader, AGoalMeasuredAfterAFaultNeedsAScenarioWithOne) {
  json j = table1();
  j.erase("objective");
  j["goals"] = {{{"metric", "ise"}, {"minimize", true}},
                {{"metric", "settling_time"}, {"threshold", 0.01}, {"minimize", true}},
                {{"metric", "peak_error_after_fault"}, {"at_most", 1}}};
  EXPECT_TRUE(errors_of(j).empty()) << to_string(errors_of(j).at(0));  // the paper's faults
  j["scenarios"][0]["faults"] = json::array();
  const std::vector<FieldError> errs = errors_of(j);
  ASSERT_EQ(errs.size(), 2u);
  EXPECT_EQ(to_string(errs[0]),
            "/goals/1/metric: settling_time is measured after a fault, and no scenario of the job "
            "has one: give a scenario faults, or goal another metric");
  EXPECT_EQ(errs[1].path, "/goals/2/metric");
}
