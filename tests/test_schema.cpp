// The JSON Schemas that `ftctune schema` prints: the committed copies in docs/ are the generated
// ones, valid files validate, and what the loader rejects the schema rejects too, where a schema
// can say it (rules between fields, such as a window inside the run, it cannot).
#include <gtest/gtest.h>

#include <fstream>
#include <functional>
#include <nlohmann/json.hpp>

#include "cli_runner.hpp"
#include "ftc/runtime/gains.hpp"
#include "ftc/tune/evaluators/tbb_evaluator.hpp"
#include "ftc/tune/job/job.hpp"
#include "ftc/tune/run/documents.hpp"
#include "short_job.hpp"

using nlohmann::json;
using namespace ftc;
using namespace ftc::testing;

namespace {

// Runs tests/schema_check.py (python3-jsonschema, installed by tools/bootstrap).
CliResult check(const std::filesystem::path& schema,
                const std::vector<std::filesystem::path>& files,
                const std::filesystem::path& scratch) {
  std::string cmd =
      "cd '" FTC_SOURCE_DIR "' && /usr/bin/python3 tests/schema_check.py '" + schema.string() + "'";
  for (const auto& f : files) cmd += " '" + f.string() + "'";
  cmd += " >'" + (scratch / "check.txt").string() + "' 2>&1";
  const int status = std::system(cmd.c_str());
  CliResult r;
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  r.out = slurp(scratch / "check.txt");
  return r;
}

void write(const std::filesystem::path& p, const json& j) { std::ofstream(p) << j.dump(2); }

}  // namespace

TEST(Schema, CommittedDocumentsAreTheGeneratedOnes) {
  const auto dir = fresh_dir("schema-docs");
  for (const char* format : {"job", "gains"}) {
    const CliResult r = run_cli(std::string("schema ") + format, dir);
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_EQ(r.out, slurp(std::string(FTC_SOURCE_DIR) + "/docs/" + format + ".schema.json"))
        << "docs/" << format << ".schema.json is stale: regenerate it with `ftctune schema "
        << format << " > docs/" << format << ".schema.json`";
  }
  EXPECT_EQ(run_cli("schema jobs", dir).exit_code, 2);
}

TEST(Schema, ShippedJobsValidate) {
  const auto dir = fresh_dir("schema-jobs");
  std::vector<std::filesystem::path> jobs;
  for (const auto& e : std::filesystem::directory_iterator(std::string(FTC_SOURCE_DIR) + "/jobs"))
    if (e.path().extension() == ".json") jobs.push_back(e.path());
  ASSERT_GE(jobs.size(), 4u);
  const CliResult r = check("docs/job.schema.json", jobs, dir);
  EXPECT_EQ(r.exit_code, 0) << r.out;
}

TEST(Schema, WhatTheLoaderRejectsTheSchemaRejects) {
  const auto dir = fresh_dir("schema-bad");
  const std::vector<std::pair<const char*, std::function<void(json&)>>> cases = {
      {"unknown key", [](json& j) { j["colour"] = "red"; }},
      {"wrong type", [](json& j) { j["scenarios"][0]["duration"] = "30"; }},
      {"missing scenarios", [](json& j) { j.erase("scenarios"); }},
      {"wrong schema", [](json& j) { j["schema"] = "ftctune.job/2"; }},
      {"Kp = 0", [](json& j) { j["controller"]["Kp"] = 0; }},
      {"alpha2 = 1", [](json& j) { j["controller"]["alpha2"] = 1; }},
      {"field of another controller", [](json& j) { j["controller"]["sigma1"] = 3; }},
      {"unknown controller", [](json& j) { j["controller"]["type"] = "pid"; }},
      {"fraction 1.5", [](json& j) { j["scenarios"][0]["faults"][1]["fraction"] = 1.5; }},
      {"key of another fault type",
       [](json& j) { j["scenarios"][0]["faults"][0]["fraction"] = 0.5; }},
      {"incipient without rate",
       [](json& j) {
         j["scenarios"][0]["faults"][0]["profile"] = {{"type", "incipient"}};
       }},
      {"unknown metric", [](json& j) { j["objective"]["metric"] = "mse"; }},
      {"population 0", [](json& j) { j["tuning"]["algorithm"]["population"] = 0; }},
      {"loudness 1.5", [](json& j) { j["tuning"]["algorithm"]["loudness"] = 1.5; }},
      {"unknown algorithm", [](json& j) { j["tuning"]["algorithm"]["type"] = "ga"; }},
      {"negative seed", [](json& j) { j["tuning"]["seed"] = -3; }},
      {"unknown tuned field",
       [](json& j) {
         j["tuning"]["parameters"]["Kd"] = {0, 1};
       }},
      {"unknown plant",
       [](json& j) {
         j["plant"] = {{"model", "boat"}};
       }},
      {"negative inertia", [](json& j) { j["plant"]["inertia"][1] = -17; }},
      {"substeps 0", [](json& j) { j["scenarios"][0]["substeps"] = 0; }},
      {"disturbance shape", [](json& j) { j["scenarios"][0]["disturbance"][0]["shape"] = "sq"; }},
  };
  std::ifstream in(std::string(FTC_SOURCE_DIR) + "/jobs/table1.json");
  const json table1 = json::parse(in);
  std::vector<std::filesystem::path> files;
  for (const auto& [what, mutate] : cases) {
    json j = table1;
    mutate(j);
    EXPECT_THROW(tune::parse_job(j, what), InputError) << what << ": the loader accepts it";
    files.push_back(dir / ("bad-" + std::to_string(files.size()) + ".json"));
    write(files.back(), j);
  }
  // One interpreter for all cases; its report has a line per file, in order.
  const CliResult r = check("docs/job.schema.json", files, dir);
  std::istringstream lines(r.out);
  std::string line;
  for (std::size_t i = 0; i < cases.size(); ++i) {
    ASSERT_TRUE(std::getline(lines, line)) << r.out;
    EXPECT_NE(line.find(": invalid at"), std::string::npos)
        << cases[i].first << ": the schema accepts it (" << line << ")";
  }
}

TEST(Schema, GainsFilesOfARunValidate) {
  const auto dir = fresh_dir("schema-gains");
  tune::TbbEvaluator evaluator(2);
  const tune::TuningOutcome r = tune::tune(tune::parse_job(short_table1_job(), "short"), evaluator);
  write(dir / "gains.json", tune::gains_document(r));
  const CliResult c = check("docs/gains.schema.json", {dir / "gains.json"}, dir);
  EXPECT_EQ(c.exit_code, 0) << c.out;
  json broken = tune::gains_document(r);
  broken["tuned"]["Kp"] = "high";
  write(dir / "broken.json", broken);
  EXPECT_EQ(check("docs/gains.schema.json", {dir / "broken.json"}, dir).exit_code, 1);
  EXPECT_THROW(runtime::parse_gains(broken, "broken.json"), InputError);
}

// Merging the validation's errors into the reader's keeps the first error of each path, in
// order, and is linear: 100 000 errors merged with 100 000 more, half of them at known paths
// (the merge compared each path with every earlier one before: 10^10 comparisons here).
TEST(Schema, MergedErrorsKeepTheFirstOfEachPathInOrder) {
  schema::Errors to, from;
  for (int i = 0; i < 100000; ++i) to.push_back({"/s/" + std::to_string(i), "read"});
  for (int i = 50000; i < 150000; ++i) from.push_back({"/s/" + std::to_string(i), "range"});
  from.push_back({"/s/149999", "range again"});
  schema::detail::dedupe_append(to, std::move(from));
  ASSERT_EQ(to.size(), 150000u);
  EXPECT_EQ(to[49999].path, "/s/49999");
  EXPECT_EQ(to[50000].message, "read");  // known: the reader's error stays
  EXPECT_EQ(to[100000].path, "/s/100000");
  EXPECT_EQ(to[100000].message, "range");
  EXPECT_EQ(to.back().path, "/s/149999");
  EXPECT_EQ(to.back().message, "range");
  schema::Errors none;
  schema::detail::dedupe_append(to, std::move(none));
  EXPECT_EQ(to.size(), 150000u);
}
