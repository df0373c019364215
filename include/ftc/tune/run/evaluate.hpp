#pragma once
// Out-of-sample evaluation (`ftctune evaluate`): the job's own controller, its compare list and
// any number of gains files, simulated on the job's listed scenarios plus its ensemble expanded
// with a held-out seed (default the ensemble's seed + 1), so that gains tuned on one set of
// members are judged on members they never saw. Members are simulated a slice at a time and
// only a few numbers per member are kept, so memory stays small however many there are.
#include <cstdint>
#include <filesystem>
#include <functional>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "ftc/sim/controller_config.hpp"
#include "ftc/sim/faults.hpp"
#include "ftc/sim/metrics_record.hpp"
#include "ftc/tune/evaluators/batch_evaluator.hpp"
#include "ftc/tune/io/files.hpp"
#include "ftc/tune/job/job.hpp"
#include "ftc/tune/problem/problem.hpp"

namespace ftc::tune {

inline constexpr const char* kEvaluationSchema = "ftctune.evaluation/1";

struct EvaluateOptions {
  struct GainsFile {
    std::filesystem::path path;
    std::string label;  // empty: the path
  };
  std::vector<GainsFile> gains;       // gains files to evaluate beside the job's controllers
  // Controllers given as they are (label, controller; source "front"), after the gains files:
  // the points of a run's front (`evaluate --front`).
  std::vector<std::pair<std::string, sim::ControllerConfig>> controllers;
  std::optional<std::uint64_t> seed;  // the ensemble's seed; default its own + 1
  std::optional<std::int64_t> count;  // members; default the ensemble's count
  // Called after each slice with the members done so far and the total.
  std::function<void(std::int64_t, std::int64_t)> progress;
};

struct MemberResult {
  std::string scenario;
  bool recoverable = true;
  double objective = 0;
  // Every field of the metrics record in the objective's window (ftc/sim/metrics_record.hpp):
  // what evaluation.json and evaluation.csv write.
  sim::MetricValues metrics;
  bool diverged = false;
  std::vector<double> goals;  // a job with goals: each goal's metric on this member, in its window
};

struct EvaluatedController {
  std::string label;
  std::string source;  // "job", "compare" or the gains file's path
  sim::ControllerConfig controller;
  Summary aggregates;
  std::vector<MemberResult> members;  // every scenario, listed then members
  // A job with goals: each goal's aggregate over the counted members (aggregate_goal), in the
  // job's order, and the hard goals' total normalised violation.
  std::vector<double> goals;
  double violation = 0;
};

struct EvaluationResult {
  Job job;
  std::uint64_t seed = 0;  // the ensemble's (0 without one)
  std::int64_t count = 0;  // ensemble members
  std::vector<EvaluatedController> controllers;
  std::int64_t simulations = 0;
};

// Throws InputError for a gains file that does not fit the job (another plant, another sample
// time) or a seed or count given for a job without an ensemble.
EvaluationResult evaluate_out_of_sample(const Job& job, const EvaluateOptions& options,
                                        BatchEvaluator& evaluator);

// evaluation.json (ftctune.evaluation/1), written piece by piece into `sink`.
void write_evaluation_json(const EvaluationResult& r, const ChunkSink& sink);
// evaluation.csv: one row per controller × scenario, with the scenario's faults in words.
void write_evaluation_csv(const EvaluationResult& r, const ChunkSink& sink);
// The table `ftctune evaluate` prints: controller, mean, median, p90, max, CVaR, diverged; for a
// job with goals, then each goal's aggregate per controller and whether it meets every limit.
std::string evaluation_table(const EvaluationResult& r);
// How many worst members write_evaluation keeps per controller.
inline constexpr std::size_t kWorstMembers = 5;
// The k worst recoverable members of a controller, worst first (ties in scenario order).
std::vector<std::size_t> worst_members(const EvaluatedController& c, std::size_t k);
// "<NN>-<label as a slug>": the controller's folder under worst/.
std::string controller_slug(const EvaluationResult& r, std::size_t controller);
// Writes evaluation.json, evaluation.csv and, per controller, its five worst recoverable
// scenarios as job files that `ftctune simulate` replays
// (worst/<NN-controller>/<rank>-<scenario>.json). The figure is the report's (draw_evaluation in
// report/evaluation.hpp).
void write_evaluation(const EvaluationResult& r, const std::filesystem::path& dir);

}  // namespace ftc::tune
