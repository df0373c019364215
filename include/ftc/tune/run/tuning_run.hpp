#pragma once
// A whole tuning run, as `ftctune run` (and the service) perform it: optimise the tuned
// parameters of the job's controller, then simulate side by side the job's `compare`
// controllers, the job's own controller (the baseline) and the tuned one, and build the output
// documents. Nothing here reads the clock or the host, so the gains file depends only on the
// job and the seed; run metadata is the caller's.
#include <cstdint>
#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "ftc/sim/controller_config.hpp"
#include "ftc/tune/job/job.hpp"
#include "ftc/tune/optimizers/optimizer.hpp"
#include "ftc/tune/evaluators/tbb_evaluator.hpp"

namespace ftc::tune {

inline constexpr const char* kGainsSchema = "ftctune.gains/1";

struct RunOptions {
  int threads = 0;                         // <= 0: all hardware threads
  std::optional<std::uint64_t> seed;       // overrides tuning.seed
  IterationObserver observer;              // progress; return false to stop
  const nlohmann::json* resume = nullptr;  // an Optimizer::state() to continue from
  bool compare = true;                     // simulate the comparison controllers after tuning
};

// Trajectories of the comparison are recorded every 10 ms of simulated time.
inline constexpr double kComparisonRecordInterval = 0.01;

struct ComparedController {
  std::string label;
  std::string role;  // "compare", "baseline" (the job's controller) or "tuned"
  sim::ControllerConfig controller;
  CandidateOutcome outcome;
};

struct TuningOutcome {
  Job job;
  std::string job_sha256;  // of the canonical JSON of the job as given
  std::uint64_t seed = 0;
  OptimizationResult optimization;
  std::vector<std::pair<std::string, double>> tuned;
  sim::ControllerConfig tuned_controller;
  std::vector<ComparedController> comparison;  // compare entries, then baseline, then tuned
  int threads = 0;
  std::int64_t simulations = 0;
  bool completed() const { return optimization.completed; }

  const ComparedController& baseline() const { return comparison[comparison.size() - 2]; }
  const ComparedController& best() const { return comparison.back(); }
};

// Throws InputError for a job that cannot be tuned. When the observer stops the run early, the
// comparison is skipped and the outcome is not completed().
TuningOutcome tune(const Job& job, const RunOptions& options = {});

std::string canonical_job_sha256(const Job& job);
std::string display_name(sim::ControllerType t);  // "PI-FOSMC", ...
// The file of a compared controller's trajectory, relative to the run directory.
std::string trajectory_file(const TuningOutcome& r, std::size_t controller, std::size_t scenario);

nlohmann::json gains_document(const TuningOutcome& r);
std::string history_csv(const TuningOutcome& r);
nlohmann::json comparison_document(const TuningOutcome& r);
std::string comparison_markdown(const TuningOutcome& r);

// The result files of a completed run, path → content: gains.json, history.csv, job.json
// (the resolved job), comparison.json, comparison.md and trajectories/<scenario>/<NN>-<label>.csv
// (one per compared controller, listed in comparison.json). The CLI and the service both write
// exactly these bytes.
std::map<std::string, std::string> output_files(const TuningOutcome& r);
// The run.json fields both `ftctune run` and the service write: threads, wall seconds,
// simulations, peak memory of the process, seed, generator. Callers add where and when.
nlohmann::json run_metadata(const TuningOutcome& r, double wall_seconds);

// Writes output_files() into `dir`, each atomically.
void write_outputs(const TuningOutcome& r, const std::filesystem::path& dir);

}  // namespace ftc::tune
