// Machine-readable command line: --json on validate, run, simulate and evaluate prints one JSON
// document of what the command did on standard output (logs stay on standard error), and
// `validate -` reads the job from standard input.
#include <gtest/gtest.h>

#include <algorithm>
#include <nlohmann/json.hpp>

#include "cli_runner.hpp"
#include "ftc/tune/io/files.hpp"
#include "ftc/tune/job/job.hpp"
#include "short_job.hpp"

using nlohmann::json;
using namespace ftc;
using namespace ftc::testing;

namespace {

// The whole of standard output as one JSON document (a stray line of text would not parse).
json document(const CliResult& r) {
  const json j = json::parse(r.out, nullptr, false);
  EXPECT_FALSE(j.is_discarded()) << "standard output is not one JSON document:\n" << r.out;
  return j;
}

}  // namespace

TEST(CliJson, ValidatePrintsTheCostAsOneDocumentAndReadsStandardInput) {
  const std::filesystem::path dir = fresh_dir("cli-json-validate");
  const std::filesystem::path file = dir / "job.json";
  tune::write_file_atomic(file, short_ensemble_job().dump(2));
  const CliResult r = run_cli("validate --json '" + file.string() + "'", dir);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const json j = document(r);
  EXPECT_EQ(j["command"], "validate");
  EXPECT_EQ(j["valid"], true);
  EXPECT_EQ(j["job"], "robust-short");
  EXPECT_EQ(j["file"], file.string());
  EXPECT_EQ(j["tuning"], true);
  EXPECT_EQ(j["evaluations"],
            tune::parse_job(short_ensemble_job(), "x").tuning->algorithm->evaluations());
  EXPECT_EQ(j["listed_scenarios"], 1);
  EXPECT_EQ(j["ensemble_members"], 6);
  EXPECT_EQ(j["scenarios"], 7);
  EXPECT_GT(j["steps_per_evaluation"].get<std::int64_t>(), 0);
  EXPECT_EQ(j["unrecoverable_scenarios"], json::array());

  // A listed scenario no gains can control is valid, and named: a warning at its path, and in
  // the document.
  json stuck = short_ensemble_job();
  stuck["scenarios"][0]["faults"] = json::parse(
      R"([{"actuator": 1, "type": "stuck", "onset": 3, "value": 0},
          {"actuator": 2, "type": "stuck", "onset": 3, "value": 0}])");
  tune::write_file_atomic(dir / "stuck.json", stuck.dump());
  const CliResult w = run_cli("validate '" + (dir / "stuck.json").string() + "'", dir);
  EXPECT_EQ(w.exit_code, 0) << w.err;
  const std::string name = stuck["scenarios"][0]["name"];
  EXPECT_NE(w.err.find("warning: /scenarios/0: scenario \"" + name + "\" is unrecoverable"),
            std::string::npos)
      << w.err;
  const CliResult wj = run_cli("validate --json '" + (dir / "stuck.json").string() + "'", dir);
  EXPECT_EQ(document(wj)["unrecoverable_scenarios"], json::array({name}));

  // The same job from standard input: the same sentence, naming "(stdin)".
  const CliResult plain = run_cli("validate '" + file.string() + "'", dir);
  const CliResult piped = run_cli("validate - < '" + file.string() + "'", dir);
  ASSERT_EQ(piped.exit_code, 0) << piped.err;
  ASSERT_EQ(plain.out.rfind(file.string() + ": ", 0), 0u) << plain.out;
  EXPECT_EQ(piped.out, "(stdin): " + plain.out.substr(file.string().size() + 2));
  const CliResult piped_json = run_cli("validate --json - < '" + file.string() + "'", dir);
  ASSERT_EQ(piped_json.exit_code, 0) << piped_json.err;
  json same = j;
  same["file"] = "(stdin)";
  EXPECT_EQ(document(piped_json), same);

  // An invalid job: exit 2, every error on stderr and, with --json, in the document.
  json bad = short_ensemble_job();
  bad["scenarios"][0]["sample_time"] = -1;
  tune::write_file_atomic(dir / "bad.json", bad.dump());
  const CliResult b = run_cli("validate --json - < '" + (dir / "bad.json").string() + "'", dir);
  EXPECT_EQ(b.exit_code, 2);
  EXPECT_NE(b.err.find("ftctune: error: (stdin): "), std::string::npos) << b.err;
  EXPECT_NE(b.err.find("/scenarios/0/sample_time: must be > 0"), std::string::npos) << b.err;
  const json e = document(b);
  EXPECT_EQ(e["valid"], false);
  EXPECT_EQ(e["source"], "(stdin)");
  ASSERT_FALSE(e["errors"].empty()) << e.dump(2);
  bool named = false;
  for (const json& x : e["errors"]) {
    named = named || (x["path"] == "/scenarios/0/sample_time" &&
                      x["message"].get<std::string>().rfind("must be > 0", 0) == 0);
    // As many errors in the document as on standard error, one line each.
    EXPECT_NE(b.err.find(x["message"].get<std::string>()), std::string::npos) << x;
  }
  EXPECT_TRUE(named) << e.dump(2);
  // Thousands of errors: the first 100 listed, one line each, and the rest counted.
  json many = short_ensemble_job();
  many["scenarios"] = json::array();
  for (int i = 0; i < 3000; ++i) many["scenarios"].push_back(json::object());
  tune::write_file_atomic(dir / "many.json", many.dump());
  const CliResult m = run_cli("validate --json '" + (dir / "many.json").string() + "'", dir);
  EXPECT_EQ(m.exit_code, 2);
  const json capped = document(m);
  ASSERT_EQ(capped["errors"].size(), tune::kMaxReportedErrors);
  const std::size_t omitted = capped["errors_omitted"];
  EXPECT_GT(omitted, 3000u);
  EXPECT_NE(m.err.find("  ... and " + std::to_string(omitted) + " more (the first 100 are listed)"),
            std::string::npos)
      << m.err.substr(0, 300);
  EXPECT_EQ(std::count(m.err.begin(), m.err.end(), '\n'), 102) << m.err.substr(0, 300);
  // Not JSON at all, from standard input.
  const CliResult junk = run_cli("validate - < /dev/null", dir);
  EXPECT_EQ(junk.exit_code, 2);
  EXPECT_NE(junk.err.find("ftctune: error: (stdin)"), std::string::npos) << junk.err;
}

TEST(CliJson, RunPrintsItsFilesAndFindingsAsOneDocument) {
  const std::filesystem::path dir = fresh_dir("cli-json-run");
  tune::write_file_atomic(dir / "job.json", tiny_job().dump(2));
  const std::filesystem::path out = dir / "run";
  const CliResult r = run_cli(
      "run --json --threads 2 '" + (dir / "job.json").string() + "' --out '" + out.string() + "'",
      dir);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("[info] iteration 1/1"), std::string::npos) << r.err;  // logs: stderr
  const json j = document(r);
  EXPECT_EQ(j["command"], "run");
  EXPECT_EQ(j["job"], "tiny");
  EXPECT_EQ(j["out"], out.string());
  EXPECT_EQ(j["gains"], (out / "gains.json").string());
  for (const json& f : j["files"])
    EXPECT_TRUE(std::filesystem::exists(out / f.get<std::string>())) << f;
  EXPECT_NE(std::find(j["files"].begin(), j["files"].end(), "gains.json"), j["files"].end());
  const json gains = json::parse(slurp(out / "gains.json"));
  EXPECT_EQ(j["tuned"], gains["tuned"]);
  EXPECT_EQ(j["controller"], "pi_fosmc");
  EXPECT_EQ(j["diverged"], false);
  EXPECT_EQ(j["fitness"], gains["fitness"]);
  EXPECT_EQ(j["objective"], gains["objective"]["value"]);
  EXPECT_EQ(j["baseline_objective"], gains["baseline"]["objective"]);
  EXPECT_EQ(j["scenarios"], 1);
  EXPECT_EQ(j["simulations"], json::parse(slurp(out / "run.json"))["simulations"]);
  EXPECT_TRUE(j["warnings"].is_array());
}

TEST(CliJson, SimulatePrintsTheMetricsItWrote) {
  const std::filesystem::path dir = fresh_dir("cli-json-simulate");
  tune::write_file_atomic(dir / "job.json", tiny_job().dump(2));
  const CliResult r = run_cli("simulate --json --set Kp=12 '" + (dir / "job.json").string() +
                                  "' --out '" + (dir / "sim").string() + "'",
                              dir);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  json j = document(r);
  EXPECT_EQ(j["command"], "simulate");
  EXPECT_EQ(j["out"], (dir / "sim").string());
  EXPECT_EQ(j["files"], json::parse(R"(["trajectory.csv", "metrics.json"])"));
  EXPECT_EQ(j["controller"]["Kp"], 12.0);
  EXPECT_FALSE(j["objective_label"].get<std::string>().empty());
  // metrics.json's content, and the rest added.
  for (const char* k : {"command", "out", "files", "objective_label"}) j.erase(k);
  EXPECT_EQ(j, json::parse(slurp(dir / "sim" / "metrics.json")));
}

TEST(CliJson, EvaluatePrintsEachControllersAggregates) {
  const std::filesystem::path dir = fresh_dir("cli-json-evaluate");
  tune::write_file_atomic(dir / "job.json", short_ensemble_job().dump(2));
  const std::filesystem::path out = dir / "ev";
  const CliResult r = run_cli("evaluate --json --no-figure --count 3 --seed 5 --threads 2 '" +
                                  (dir / "job.json").string() + "' --out '" + out.string() + "'",
                              dir);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const json j = document(r);
  EXPECT_EQ(j["command"], "evaluate");
  EXPECT_EQ(j["out"], out.string());
  EXPECT_EQ(j["files"], json::parse(R"(["evaluation.json", "evaluation.csv", "worst"])"));
  EXPECT_EQ(j["seed"], 5);
  EXPECT_EQ(j["count"], 3);
  const json doc = json::parse(slurp(out / "evaluation.json"));
  ASSERT_EQ(j["controllers"].size(), doc["controllers"].size());
  for (std::size_t c = 0; c < doc["controllers"].size(); ++c) {
    EXPECT_EQ(j["controllers"][c]["label"], doc["controllers"][c]["label"]);
    EXPECT_EQ(j["controllers"][c]["aggregates"], doc["controllers"][c]["aggregates"]);
  }
  EXPECT_GT(j["simulations"].get<std::int64_t>(), 0);
  for (const json& f : j["files"])
    EXPECT_TRUE(std::filesystem::exists(out / f.get<std::string>())) << f;
}
