#pragma once
// The run API: what `ftctune run`, `study`, `evaluate`, `landscape` and `simulate` do, as library calls that
// the command line, the service and the Python module share. Each takes a loaded job and an
// options struct whose defaults are those of the command line; each chooses the evaluator (all
// ranks' threads under mpirun, else this machine's threads) unless given one, handles its output
// directory and writes the same files, byte for byte, as the command. Messages for people go to
// the options' `log` (nothing when it is empty); what the command prints on standard output is
// the caller's, from the result. Bad input throws InputError (with its JSON path or option).
#include <cstdint>
#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "ftc/tune/evaluators/batch_evaluator.hpp"
#include "ftc/tune/job/job.hpp"
#include "ftc/tune/report/landscape.hpp"
#include "ftc/tune/run/landscape.hpp"
#include "ftc/tune/report/report.hpp"
#include "ftc/tune/run/checkpoint.hpp"
#include "ftc/tune/run/evaluate.hpp"
#include "ftc/tune/run/front.hpp"
#include "ftc/tune/api/run_directory.hpp"
#include "ftc/tune/run/tuning_run.hpp"

namespace ftc::tune {

// ---- The evaluator ---------------------------------------------------------------------------

// The MPI job this process is a rank of (`mpirun -np N ftctune ...`), from MPI_Init to
// MPI_Finalize; nothing at all for a process not started by an MPI launcher. Rank 0 runs the
// command; the other ranks serve() it until it finishes. At most one per process.
class Ranks {
 public:
  Ranks(int& argc, char**& argv);
  ~Ranks();
  Ranks(const Ranks&) = delete;
  Ranks& operator=(const Ranks&) = delete;
  bool leader() const { return rank_ == 0; }
  // Started by mpirun, but built without MPI (the message is printed): exit 2.
  bool failed() const { return failed_; }
  int serve();  // a worker rank's whole life; its exit code

 private:
  int rank_ = 0, size_ = 1;
  bool failed_ = false;
};
// Processes taking part in the simulations: the MPI job's ranks, or 1.
int mpi_ranks();
// The evaluator of a command's simulations: all ranks' threads under mpirun (`threads` per
// rank), else this machine's `threads` (<= 0: every core). Throws InputError for a bad
// FTCTUNE_RANK_TIMEOUT (seconds a rank holding work may stay silent; default 10).
std::unique_ptr<BatchEvaluator> make_evaluator(int threads);

// "Kp = 12, Ki = 3": tuned values by name, five digits, as the command line prints them.
std::string parameters_text(const std::vector<std::string>& names, const Decision& x);

// ---- run and resume --------------------------------------------------------------------------

enum class CheckpointPolicy {
  automatic,        // after every iteration once the run looks like taking over a minute
  every_iteration,  // after every iteration, from the first (--checkpoint)
  never             // --no-checkpoint
};

// What the run API tells after every iteration of a run.
struct IterationReport {
  const HistoryRow& row;
  std::int64_t total_evaluations = 0;  // of the whole run
  int iterations = 0;                  // of the whole run
  double elapsed = 0.0, eta = 0.0;     // seconds, of this process
  // A job with two or more soft goals: the points of the front of the trials so far (row's best
  // is then only the least first soft goal, not "the best").
  std::optional<std::size_t> front_points;
};

struct RunJobResult;

// Where a run keeps what it writes: the checkpoint it continues from, the one after each
// iteration, and its finished files. run_job() and resume_job() use the run's output directory
// (the command line and Python: checkpoint.json, and the files staged, then moved into place with
// gains.json last) unless they are given another, as the service gives its job store.
class RunStorage {
 public:
  virtual ~RunStorage() = default;
  // Where the checkpoints go, for messages ("out/table1/checkpoint.json").
  virtual std::string checkpoint_name() const = 0;
  // Called once before the run: the checkpoint to continue from (its iteration and its
  // RunOptions::resume state), or nullopt to start from the first iteration. Throws InputError
  // for a checkpoint that is damaged or of another job or seed.
  virtual std::optional<Checkpoint> load_checkpoint(const std::string& job_sha256,
                                                    std::uint64_t seed) = 0;
  // After iteration h, when the run checkpoints: what a resume needs (run_checkpoint() of the
  // optimiser and every trial so far; a storage may keep only the trials new since its last
  // call). False stops the run (RunJobResult::stopped), as on_iteration's false does.
  virtual bool save_checkpoint(const std::string& job_sha256, std::uint64_t seed,
                               const HistoryRow& h, const Optimizer& optimizer,
                               const std::vector<Trial>& trials) = 0;
  // For a job with two or more soft goals, before each iteration's save_checkpoint: the size of
  // the front of the trials so far, which the run has found for its own report (a storage that
  // records progress need not find it again).
  virtual void front_so_far(std::size_t /*points*/) {}
  // Its own fields of run.json (the service's job id and attempts), added before it is written.
  virtual void describe(nlohmann::json& run) const { (void)run; }
  // The files of a finished run, or of a stopped one kept partial (RunJobOptions::keep_partial):
  // name -> content, output_files() with run.json (and history-random.csv with a baseline).
  virtual void put(const RunJobResult& result, const std::map<std::string, std::string>& files) = 0;
};

struct RunJobOptions {
  // The job's file, as run.json records it (job_file) and errors name it.
  std::string job_file;
  // Empty: out/<job name>, or out/<job name>-2, -3, ... when that holds a run (with a warning).
  // A directory given here that holds a run is refused unless `force`.
  std::filesystem::path out;
  int threads = 0;                    // <= 0: every core (per rank under mpirun)
  std::optional<std::uint64_t> seed;  // instead of the job's tuning.seed
  bool baseline = false;              // also random search with the same budget
  bool capping = true;                // exact capping of hopeless candidates (issue 27)
  bool cache = true;                  // no decision vector simulated twice (issue 43)
  bool force = false;                 // replace the run `out` holds
  bool resume = false;                // continue the run in `out` from its checkpoint
  // false: no output directory at all (no lock, checkpoint or file); write_run() writes the
  // result's files later.
  bool write = true;
  CheckpointPolicy checkpoint = CheckpointPolicy::automatic;
  double checkpoint_after_seconds = 60.0;  // for CheckpointPolicy::automatic
  BatchEvaluator* evaluator = nullptr;     // null: make_evaluator(threads)
  // Called after every iteration (after the checkpoint is written); false stops the run, which
  // then writes no files (its checkpoint, if it wrote one, stays for a resume).
  std::function<bool(const IterationReport&)> on_iteration;
  // Asked between packs of simulations (RunOptions::interrupt: cheap and thread-safe): true
  // stops the run within its iteration, which ends as if on_iteration had stopped it after the
  // iteration before (its checkpoint, when it writes them, is the last). Null: a run stops
  // between iterations only.
  std::function<bool()> interrupt;
  // Asked when the run was stopped (by on_iteration, interrupt or the storage): true
  // keeps its files so far, its best compared as a finished run's best is (compare_best), with
  // gains.json recording optimizer.completed false and run.json "completed": false. Null: none.
  std::function<bool()> keep_partial;
  // Null: the output directory `out` (with `write`). Else the checkpoints and files go to it, and
  // out, force and write do not apply; it is resumed whenever it holds a checkpoint.
  RunStorage* storage = nullptr;
  // At most this many rows per comparison trajectory (0: no limit; RunOptions's).
  std::int64_t max_trajectory_rows = 0;
  RunLog log;
};

struct RunJobResult {
  TuningOutcome outcome;
  std::optional<TuningOutcome> random_baseline;  // with RunJobOptions::baseline
  std::filesystem::path out;                     // where the files went (empty: not written)
  std::vector<std::string> files;                // as run.json lists them
  std::string run_json;                          // run.json's text
  double wall_seconds = 0.0;
  bool stopped = false;  // on_iteration, interrupt or the storage stopped it: nothing was written...
  bool partial = false;  // ...but what keep_partial kept (the files of a partial run)
  // No candidate met the job's hard goals (fitness < 0, the constraint rule's): gains.json holds
  // the least violating one (the command line exits 3).
  bool infeasible() const { return outcome.optimization.best_fitness < 0.0; }
  // Every candidate diverged (fitness 0), or none is feasible: gains.json holds gains that must
  // not be deployed (the command line exits 3).
  bool diverged() const { return !(outcome.optimization.best_fitness > 0.0); }
};

// `ftctune run`: tunes the job, then writes its files into the output directory, locked for the
// run: first into a staging directory inside it, then moved into place with gains.json last (a
// run stopped on the way leaves the earlier files as they were). Throws InputError for a job
// without a tuning section, one over the memory budget, or an output directory that holds a run
// (without force) or that another run is writing.
RunJobResult run_job(const Job& job, const RunJobOptions& options = {});
// Every file of a finished (or partial) run_job() result, name -> content: output_files(), run.json
// as the result holds it, and history-random.csv with a baseline. What the storage is given.
std::map<std::string, std::string> run_files(const RunJobResult& result);
// The files of a finished run_job() result into `out`, as run_job writes them (the same bytes;
// run.json as the result holds it): `out` is locked, refused when it holds a run unless `force`
// (InputError "--out"), and the files go through a staging directory, gains.json last. For a
// run computed with `write = false`. Returns the directory. Throws InputError for a stopped run.
std::filesystem::path write_run(const RunJobResult& result, const std::filesystem::path& out,
                                bool force = false, const RunLog& log = {});
// `ftctune run --resume`: run_job with options.resume; continues from `out`'s checkpoint, or
// starts from the first iteration when there is none. Refuses a directory holding a finished run,
// a checkpoint of another job or seed, and force.
RunJobResult resume_job(const Job& job, RunJobOptions options = {});

// ---- study -----------------------------------------------------------------------------------

struct StudyOptions {
  std::string job_file;                 // errors name it, and study.md's command
  std::vector<std::string> algorithms;  // bat, random, pagmo:<name>; each once
  std::vector<std::uint64_t> seeds;     // each once
  std::int64_t budget = 0;              // evaluations per run, the initial population included
  int threads = 0;
  std::filesystem::path out;  // empty: out/<job name>/study
  // How study.md names the seeds and the command; empty: the lists joined by commas.
  std::string seeds_text, command;
  BatchEvaluator* evaluator = nullptr;
  RunLog log;
};

struct StudyRun {
  std::string algorithm;
  std::uint64_t seed = 0;
  double objective = 0.0;  // of the best candidate, 1/J; +inf when every candidate diverged
  Decision best;
  int on_bound = 0;
  std::int64_t evaluations = 0;
  double wall = 0.0;
};

struct StudyRow {
  std::string algorithm;
  int rank = 1;  // entries whose medians lie within the noise floor of each other share one
  double median = 0, best = 0, worst = 0, wall = 0;
  int on_bound = 0, parameters = 0;
  std::int64_t evaluations = 0;  // the most any run spent
};

struct StudyResult {
  std::vector<StudyRun> runs;  // algorithm by algorithm, seed by seed
  std::vector<StudyRow> rows;  // sorted by median
  double noise = 0.0;          // the best run's relative noise floor
  std::filesystem::path out, csv, markdown, figure;
};

// "bat,random,pagmo:cmaes": the names, each known and given once (InputError "--algorithms").
std::vector<std::string> parse_algorithm_list(const std::string& text);
// "1-10", "1,3,5", "1-3,7": the seeds in the order given, each once (InputError "--seeds").
std::vector<std::uint64_t> parse_seed_list(const std::string& text);
// `ftctune study`: the job's tuning with each algorithm and seed at one budget; writes
// study.csv, study.md and study.png into the output directory.
StudyResult run_study(const Job& job, const StudyOptions& options);
// The table of study.md (and of the command's output).
std::string study_table(const std::vector<StudyRow>& rows);

// ---- evaluate --------------------------------------------------------------------------------

struct EvaluateJobOptions {
  std::vector<EvaluateOptions::GainsFile> gains;
  std::optional<std::uint64_t> seed;  // the ensemble's; default its own + 1
  std::optional<std::int64_t> count;  // members; default the ensemble's count
  // Empty: <the job's latest run>/evaluation, else out/<job name>/evaluation.
  std::filesystem::path out;
  int threads = 0;
  bool figure = true;  // draw the figure (gnuplot)
  // A run directory of the job with a front (front.json): every point of it is evaluated too,
  // and the held-out front goes to out/front.json (run/front.hpp's held_out_front).
  std::filesystem::path front;
  BatchEvaluator* evaluator = nullptr;
  std::function<void(std::int64_t, std::int64_t)> progress;  // members done, total
  RunLog log;
};

struct EvaluateJobResult {
  EvaluationResult evaluation;
  std::filesystem::path out, figure;  // figure: empty without one
  int threads = 0;                    // the evaluator's concurrency
  std::optional<Front> front;         // with EvaluateJobOptions::front: the held-out front
  std::filesystem::path front_figure;  // its figure (draw_held_out_front); empty without one
};

// The directory `ftctune evaluate` writes into when none is given (logs which run it chose).
std::filesystem::path evaluation_dir(const Job& job, const RunLog& log = {});
// `ftctune evaluate`: evaluate_out_of_sample, then evaluation.json, evaluation.csv, worst/ and
// the figure.
EvaluateJobResult evaluate_job(const Job& job, const EvaluateJobOptions& options);

// ---- landscape -------------------------------------------------------------------------------

// The grid (ftc/tune/run/landscape.hpp) and its figure (ftc/tune/report/landscape.hpp).
struct LandscapeOptions : LandscapeGrid, LandscapeFigureOptions {};

struct LandscapeResult {
  std::filesystem::path csv, figure;
  std::vector<std::string> params;
  std::int64_t simulations = 0;
  double best_objective = 0.0;
  std::vector<double> best;  // grid point with the lowest objective
  // The unplotted tuned parameters and the values they were held at.
  std::vector<std::pair<std::string, double>> fixed;
  std::string fixed_source;
  // History rows drawn, and those of them that lie on the map (their unplotted parameters at
  // the fixed values); the others are drawn projected.
  int path_points = 0, path_on_map = 0;
};

// Evaluates the job's objective on the grid (evaluate_landscape), writes
// `out_dir`/landscape.csv and draws the figure beside it (draw_landscape).
LandscapeResult compute_landscape(const Job& job, const std::filesystem::path& out_dir,
                                  const LandscapeOptions& options, BatchEvaluator& evaluator);

struct LandscapeJobOptions {
  int n1 = 41, n2 = 41;             // grid points per parameter
  std::vector<std::string> params;  // two tuned parameters; default: the first two
  // Empty: <the job's latest run>/landscape, else out/<job name>/landscape. One that holds a
  // landscape is refused unless `force`.
  std::filesystem::path out;
  std::filesystem::path history;  // empty: the latest run's history.csv, if any
  FigureFormat format = FigureFormat::png;
  int threads = 0;
  bool force = false;
  // Hold the unplotted tuned parameters at the job's values instead of the latest run's tuned
  // ones.
  bool at_job_values = false;
  BatchEvaluator* evaluator = nullptr;
  std::function<void(std::int64_t, std::int64_t)> progress;  // grid points done, total
  RunLog log;
};

struct LandscapeJobResult {
  LandscapeResult landscape;
  std::filesystem::path out;
};

// `ftctune landscape`: the objective on a grid over two tuned parameters, beside the job's
// latest run (its tuned values and noise floor, its best-so-far path drawn on top).
LandscapeJobResult landscape_job(const Job& job, const LandscapeJobOptions& options = {});

// ---- simulate --------------------------------------------------------------------------------

struct SimulateJobOptions {
  double record_every = 0.01;  // seconds between the trajectory's rows (> 0)
  // Empty: out/<job name>/simulate. The files land there only when `write`.
  std::filesystem::path out;
  bool write = true;
  std::function<void()> after_scenario;  // called between scenarios (Python's signal check)
};

struct SimulateJobResult {
  sim::ControllerConfig controller;
  Evaluation evaluation;  // its scenarios: each listed scenario's metrics, in the job's order
  int counted = 0;  // scenarios the objective counts (unrecoverable ones are left out)
  // metrics.json: the controller, the objective and fitness (null when no scenario counts), and
  // per scenario its metrics, whether it is recoverable and whether it counts.
  nlohmann::json document;
  // The trajectory files, name -> CSV: trajectory.csv for the first scenario, then
  // trajectory-<name>.csv. The CSV is empty when the file was written (`write`): a scenario's
  // trajectory is written as soon as it is simulated, and not kept.
  std::vector<std::pair<std::string, std::string>> trajectories;
  std::filesystem::path out;  // where the files went (when written)
  std::vector<std::string> warnings;  // diverged and unrecoverable scenarios, for people
};

// `ftctune simulate`: the controller on every listed scenario of the job, scored by the job's
// objective; metrics.json and the trajectories into the output directory.
SimulateJobResult simulate_job(const Job& job, const sim::ControllerConfig& controller,
                               const SimulateJobOptions& options = {});

}  // namespace ftc::tune
