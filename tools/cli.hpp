#pragma once
// Shared pieces of the ftctune command line. Each command registers its CLI11 subcommand and
// returns the function that runs it once the arguments are parsed.
#include <CLI/CLI.hpp>
#include <filesystem>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "ftc/sim/controller_config.hpp"
#include "ftc/tune/evaluators/batch_evaluator.hpp"
#include "ftc/tune/job/job.hpp"

namespace ftc::cli {

struct Globals {
  bool quiet = false;
  bool verbose = false;
};

using Action = std::function<int()>;

void add_simulate_command(CLI::App& app, const Globals& g, Action& action);
void add_run_command(CLI::App& app, const Globals& g, Action& action);
void add_validate_command(CLI::App& app, const Globals& g, Action& action);
void add_serve_command(CLI::App& app, const Globals& g, Action& action);
void add_client_commands(CLI::App& app, const Globals& g, Action& action);
void add_report_commands(CLI::App& app, const Globals& g, Action& action);
void add_schema_command(CLI::App& app, const Globals& g, Action& action);
void add_study_command(CLI::App& app, const Globals& g, Action& action);
void add_ensemble_command(CLI::App& app, const Globals& g, Action& action);
void add_evaluate_command(CLI::App& app, const Globals& g, Action& action);

// The MPI job this process is a rank of (`mpirun -np N ftctune ...`), from MPI_Init to
// MPI_Finalize; nothing at all for a process not started by an MPI launcher. Rank 0 runs the
// command; the other ranks serve() it until it finishes.
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
std::unique_ptr<tune::BatchEvaluator> make_evaluator(int threads);

// Renders the report of a run directory; format html, png or svg.
int render_run_report(const std::string& dir, const std::string& format, bool quiet);

// The controller selected by --controller TYPE (Table 1 defaults) or the job's own, with
// --set KEY=VALUE overrides; throws InputError (source "--set") naming the offending key.
sim::ControllerConfig select_controller(const tune::Job& job, const std::string& type,
                                        const std::vector<std::string>& sets);

// Checks of option values, run while the command line is parsed (so a bad value is exit 2
// before any work): a seed in 0..2^64-1 (CLI11 alone reads -1 as 2^64-1), a directory that
// exists or can be created and written, a file that can be created in its directory.
CLI::Validator seed_value();
CLI::Validator output_directory();
CLI::Validator output_file();

// Default output directory of a job: out/<job name>.
std::filesystem::path default_out_dir(const tune::Job& job);
std::filesystem::path default_out_dir_for(const std::string& job_name);

// The latest finished run of a job: of out/<name>, out/<name>-2, -3, ... (where `run` writes
// when the earlier ones hold a run), the one whose gains.json is newest among those of this job
// (the same canonical SHA-256), else the newest of any job of that name. Empty when there is
// none. `why` says which it chose and why, for the log.
std::filesystem::path latest_run_dir(const tune::Job& job, std::string* why = nullptr);

}  // namespace ftc::cli
