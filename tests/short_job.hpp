#pragma once
// A shortened copy of the Table 1 job for fast end-to-end tests: 5 s with the faults at 2 s
// and 3.5 s, 3 bats × 2 iterations.
#include <cstdint>
#include <fstream>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "ftc/tune/evaluators/tbb_evaluator.hpp"
#include "ftc/tune/job/job.hpp"
#include "ftc/tune/run/tuning_run.hpp"

namespace ftc::testing {

inline nlohmann::json short_table1_job() {
  std::ifstream in(std::string(FTC_SOURCE_DIR) + "/jobs/table1.json");
  nlohmann::json j = nlohmann::json::parse(in);
  j["name"] = "table1-short";
  j["scenarios"][0]["duration"] = 5;
  j["scenarios"][0]["faults"][0]["onset"] = 2;
  j["scenarios"][0]["faults"][1]["onset"] = 3.5;
  j["objective"]["window"] = {0, 5};
  j["tuning"]["algorithm"]["population"] = 3;
  j["tuning"]["algorithm"]["iterations"] = 2;
  return j;
}

// A shortened copy of jobs/robust-faults.json: 6 members of 10 s with onsets in [3, 5] s, scored
// over the 4 s after each member's first fault; 3 bats × 2 iterations.
inline nlohmann::json short_ensemble_job() {
  std::ifstream in(std::string(FTC_SOURCE_DIR) + "/jobs/robust-faults.json");
  nlohmann::json j = nlohmann::json::parse(in);
  j["name"] = "robust-short";
  j["scenarios"][0]["duration"] = 10;
  j["scenarios"][0]["faults"][0]["onset"] = 3;
  j["scenarios"][0]["faults"][1]["onset"] = 4;
  j["ensemble"]["count"] = 6;
  j["ensemble"]["faults"]["onset"] = {{"uniform", {3, 5}}};
  j["objective"]["window"] = {0, 4};
  j["tuning"]["algorithm"]["population"] = 3;
  j["tuning"]["algorithm"]["iterations"] = 2;
  return j;
}

// A job of two soft goals (ISE and control TV) and one hard goal, on the short Table 1 job with
// Kp and the switching gain tuned (the latter on a log scale): 4 bats x 3 iterations. The front
// tests run it; the front fuzz target reads fronts of its runs.
inline nlohmann::json front_job() {
  nlohmann::json j = short_table1_job();
  j["name"] = "front-short";
  j.erase("objective");
  j["goals"] = {{{"metric", "ise"}, {"window", {0, 5}}, {"minimize", true}},
                {{"metric", "control_tv"}, {"minimize", true}},
                {{"metric", "peak_command"}, {"at_most", 1e6}}};
  j["tuning"]["parameters"] = {{"Kp", {1, 50}},
                               {"switching_gain", {{"bounds", {2, 200}}, {"scale", "log"}}}};
  j["tuning"]["algorithm"] = {{"type", "bat"}, {"population", 4}, {"iterations", 3}};
  return j;
}

// Tiny: 2 bats × 1 iteration on 50 ms of simulated time.
inline nlohmann::json tiny_job(const std::string& name = "tiny") {
  nlohmann::json j = short_table1_job();
  j["name"] = name;
  j["scenarios"][0]["duration"] = 0.05;
  j["scenarios"][0]["faults"][0]["onset"] = 0.01;
  j["scenarios"][0]["faults"][1]["onset"] = 0.03;
  j["objective"]["window"] = {0, 0.05};
  j["tuning"]["algorithm"]["population"] = 2;
  j["tuning"]["algorithm"]["iterations"] = 1;
  return j;
}

inline tune::Job short_job() { return tune::parse_job(short_table1_job(), "short"); }

// A tuning run on `threads` TBB workers.
inline tune::TuningOutcome tuned(const tune::Job& job, int threads,
                                 std::optional<std::uint64_t> seed = std::nullopt,
                                 const tune::RunOptions& base = {}) {
  tune::TbbEvaluator evaluator(threads);
  tune::RunOptions o = base;
  o.seed = seed;
  return tune::tune(job, evaluator, o);
}

// The checkpoint of a run of `job` on one thread stopped after iteration `last`: what a resumed
// run starts from.
inline nlohmann::json checkpoint_after(const tune::Job& job, int last) {
  std::string checkpoint;
  tune::RunOptions stop;
  stop.observer = [&](const tune::HistoryRow& h, const tune::Optimizer& o,
                      const std::vector<tune::Trial>& trials) {
    checkpoint = tune::run_checkpoint(o, trials).dump();
    return h.iteration < last;
  };
  tuned(job, 1, std::nullopt, stop);
  return nlohmann::json::parse(checkpoint);
}

}  // namespace ftc::testing
