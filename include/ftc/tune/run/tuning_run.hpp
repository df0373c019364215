#pragma once
// A whole tuning run, as `ftctune run` (and the service) perform it: optimise the tuned
// parameters of the job's controller, then simulate side by side the job's `compare`
// controllers, the job's own controller (the baseline) and the tuned one. Nothing here reads the
// clock or the host, so the outcome depends only on the job and the seed; run metadata is the
// caller's. The documents a run writes are in run/documents.hpp.
#include <cstdint>
#include <functional>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "ftc/sim/controller_config.hpp"
#include "ftc/tune/evaluators/batch_evaluator.hpp"
#include "ftc/tune/job/job.hpp"
#include "ftc/tune/optimizers/optimizer.hpp"
#include "ftc/tune/problem/problem.hpp"
#include "ftc/tune/run/front.hpp"

namespace ftc::tune {

// Called after every iteration with the trials so far (all of them, those before a resume
// included); return false to stop.
using RunObserver =
    std::function<bool(const HistoryRow&, const Optimizer&, const std::vector<Trial>& trials)>;

struct RunOptions {
  std::optional<std::uint64_t> seed;  // overrides tuning.seed
  RunObserver observer;               // progress and checkpoints
  // A run_checkpoint() to continue from (or, as older service stores hold, a bare
  // Optimizer::state(): then trials.csv starts at the resume).
  const nlohmann::json* resume = nullptr;
  bool compare = true;  // simulate the comparison controllers after tuning
  // At most this many rows per comparison trajectory (0: no limit): a longer scenario is
  // recorded at a coarser interval than kComparisonRecordInterval. The metrics do not change.
  std::int64_t max_trajectory_rows = 0;
  // Exact capping of hopeless candidates (issue 27, ProblemFitness::evaluate_capped; fronts,
  // issue 42: objective_vectors_capped): the same gains, history, front and checkpointed
  // optimiser state either way; trials.csv marks capped trials.
  bool capping = true;
  // The cache (issue 43, ProblemFitness::set_cache): a decision vector already simulated is not
  // simulated again; the same gains, history and front either way; trials.csv marks the rows it
  // served.
  bool cache = true;
  // A stop within an iteration (BatchEvaluator::set_interrupt: asked between packs, from worker
  // threads, so an atomic flag): the run ends at its last completed iteration, as if the
  // observer had stopped it there (the optimiser's state and trials as they were then), and the
  // outcome says interrupted. Only the tuning is interrupted, never the comparison.
  std::function<bool()> interrupt;
};

// What a run needs to continue after an iteration: the optimiser's state and every trial so
// far, so that the resumed run writes the same gains file and the same trials.csv.
nlohmann::json run_checkpoint(const Optimizer& optimizer, const std::vector<Trial>& trials);
// The "trials" part of a checkpoint for trials[from..]: a store that keeps each iteration's new
// trials beside the optimiser's state writes O(trials) in all, not O(trials²).
nlohmann::json trials_json(const std::vector<Trial>& trials, std::size_t from = 0);
// The trials of a checkpoint's "trials" (rows of a job with `goals` goals); InputError at
// /trials if they are not rows trials_json wrote.
std::vector<Trial> trials_from_json(const nlohmann::json& rows, std::size_t goals);

// Trajectories of the comparison are recorded every 10 ms of simulated time.
inline constexpr double kComparisonRecordInterval = 0.01;
// The samples between recorded rows of the comparison's trajectories: 10 ms, or coarser so that
// no trajectory has more than `max_rows` rows (0: no limit).
std::int64_t comparison_record_every(const Job& job, std::int64_t max_rows = 0);

struct ComparedController {
  std::string label;
  std::string role;  // "compare", "baseline" (the job's controller) or "tuned"
  sim::ControllerConfig controller;
  CandidateOutcome outcome;
  Summary summary;  // over every scenario, members included
};

// SPEC §14: the winner re-evaluated with its initial states nudged by a relative 1e-12. After
// a fault the closed loop is chaotic at rounding level, so objectives closer than this spread
// are not told apart by merit.
struct NoiseFloor {
  double perturbation = 1e-12;
  int repeats = 8;
  double objective_min = 0.0, objective_max = 0.0;
  double relative_spread = 0.0;  // (max - min) / the winner's objective
  // With sensors (SPEC §18): the repeats also run with other sensor seeds, listed here, and the
  // spread has two parts, each (max - min) / the winner's objective over its own runs: the
  // nudged initial states' (rounding) and the sensor seeds' (measurement noise).
  std::vector<std::uint64_t> sensor_seeds;
  double rounding_spread = 0.0, sensor_spread = 0.0;
};
inline constexpr std::uint64_t kNoiseFloorStream = 1000000;  // member k = 1e6 + r of §12

// What a run evaluates after its last iteration, in candidate evaluations (each on every
// scenario): the comparison (the compare entries, the job's own controller and the tuned one) and
// the noise floor (NoiseFloor::repeats reruns of the tuned gains, or of each of the front's
// `front_points` points). Not counted: the check of a tuned value on a search bound, one more
// evaluation per such parameter.
std::int64_t finishing_evaluations(const Job& job, std::size_t front_points = 0);

struct TuningOutcome {
  Job job;
  std::string job_sha256;  // of the canonical JSON of the job as given
  std::uint64_t seed = 0;
  AlgorithmPtr algorithm;           // the settings the optimiser ran with
  OptimizationResult optimization;  // best and history in parameter values (not ln x)
  std::vector<Trial> trials;        // every evaluated candidate (since the resume, if resumed)
  std::vector<std::pair<std::string, double>> tuned;
  sim::ControllerConfig tuned_controller;
  std::vector<ComparedController> comparison;  // compare entries, then baseline, then tuned
  std::optional<NoiseFloor> noise_floor;       // with the comparison
  // A job with two or more soft goals: the front of all trials, its hypervolume after each
  // iteration (history.csv) and the picked point (run/front.hpp); the tuned controller is the
  // picked point's.
  std::optional<Front> front;
  std::vector<double> hypervolume;
  // Things a user should act on, one sentence each: a tuned parameter that ended within 0.1 % of
  // its search range from a bound (the optimum may lie beyond it); a compared controller that
  // scores better; a much larger control TV than the job's own gains' (comparison_warnings).
  std::vector<std::string> warnings;
  // What the problem scored: its scenarios (listed, then members) and which it left out.
  std::size_t scenarios = 0, listed_scenarios = 0;
  int unrecoverable = 0, left_out = 0;
  std::vector<bool> listed_recoverable;  // per listed scenario (SPEC §12)
  int threads = 0;                       // the evaluator's concurrency
  std::vector<int> threads_per_rank;     // its threads on each MPI rank (one entry without MPI)
  std::string evaluator;                 // its name
  std::int64_t simulations = 0;
  // RunOptions::interrupt cut an iteration short: the outcome is of the iterations before it
  // (none, when it came during the first: optimization.history is empty then).
  bool interrupted = false;
  bool completed() const { return optimization.completed; }

  const ComparedController& baseline() const { return comparison[comparison.size() - 2]; }
  const ComparedController& best() const { return comparison.back(); }
};

// Tunes a problem with a given optimiser (made with `algorithm` and `seed`, which the outcome
// records), simulating through `evaluator`. When the observer stops the run early, the
// comparison is skipped and the outcome is not completed().
TuningOutcome tune(const TuningProblem& problem, Optimizer& optimizer, AlgorithmPtr algorithm,
                   std::uint64_t seed, BatchEvaluator& evaluator, const RunOptions& options = {});
// The job's own algorithm, seeded by options.seed or tuning.seed. Throws InputError for a job
// that cannot be tuned.
TuningOutcome tune(const Job& job, BatchEvaluator& evaluator, const RunOptions& options = {});

// The outcome of a run stopped at a checkpoint (run_checkpoint(), or a bare Optimizer::state()):
// its history, trials and best so far, in parameter values, without a comparison; completed()
// only when the checkpoint is of the last iteration. Throws InputError for a damaged one.
TuningOutcome checkpoint_outcome(const Job& job, const nlohmann::json& checkpoint,
                                 std::optional<std::uint64_t> seed = std::nullopt);
// Compares the best so far of a run stopped early as tune() compares a completed run's (the job's
// compare entries, its own controller, the best; the noise floor), so that output_files() gives
// the files of a partial run: gains.json records optimizer.completed false, which the gains
// loader refuses. Does nothing to an outcome that has its comparison or no iteration.
void compare_best(TuningOutcome& r, BatchEvaluator& evaluator, std::int64_t max_trajectory_rows = 0);

// Whether the tuned controller's margin over the job's own is larger than the noise floor, in one
// sentence for people (empty without a comparison).
std::string noise_floor_sentence(const TuningOutcome& r);

// The warnings of tuned values at a bound: within 0.1 % of the search range (in ln x for a
// log-scale parameter) from the lower or upper bound.
std::vector<std::string> bound_warnings(const Job& job, const Decision& values);
// The same, told per parameter on a bound how much the objective changes (relative) when that
// parameter moves 1 % of its range inward (inward_value): within the noise floor the warning
// says the objective is flat there instead of advising to widen the bound.
std::vector<std::string> bound_warnings(const Job& job, const Decision& values,
                                        const std::vector<std::optional<double>>& inward_change,
                                        double noise_floor);
// A value 1 % of the search range (in ln x on a log scale) inward from the bound `x` lies on;
// nullopt when x is on neither bound.
std::optional<double> inward_value(const ParameterBounds& bounds, double x);

// The warnings of a finished comparison. Of the tuned loop on each listed scenario: it left the
// model's validity, diverged, never settled after the fault (settling_time +inf, when the job's
// metrics block gives a settling threshold), or ended farther from the reference than it started
// (|X1| at its last recorded sample above |X1(0)| and the job's metrics.drift_warning, default
// kDriftWarningFloor). Then a compared controller whose objective is lower than the tuned one's,
// and tuned gains whose control TV on the listed scenarios exceeds metrics.control_tv_warning
// (default kControlTvWarningRatio) times the job's own gains'.
inline constexpr double kControlTvWarningRatio = 3.0;
// A tuned loop that ends a listed scenario farther from the reference than it started, and
// farther than this (in the plant's position unit, rad for every shipped plant), is warned of.
inline constexpr double kDriftWarningFloor = 0.1;
std::vector<std::string> comparison_warnings(const TuningOutcome& r);

std::string canonical_job_sha256(const Job& job);
std::string display_name(sim::ControllerType t);  // "PI-FOSMC", ...

}  // namespace ftc::tune
