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
#include "ftc/tune/api/api.hpp"

namespace ftc::cli {

struct Globals {
  bool quiet = false;
  bool verbose = false;
  // --plant-path: directories searched for a job's plant plugins before FTCTUNE_PLANT_PATH's.
  std::vector<std::string> plant_path;
  // serve --plugin: the plugins a server loads on every MPI rank before anything else, after
  // which no rank loads a library by name.
  std::vector<std::string> plugins;
};

using Action = std::function<int()>;

void add_simulate_command(CLI::App& app, const Globals& g, Action& action);
void add_run_command(CLI::App& app, const Globals& g, Action& action);
void add_validate_command(CLI::App& app, const Globals& g, Action& action);
void add_serve_command(CLI::App& app, Globals& g, Action& action);
void add_client_commands(CLI::App& app, const Globals& g, Action& action);
void add_report_commands(CLI::App& app, const Globals& g, Action& action);
void add_schema_command(CLI::App& app, const Globals& g, Action& action);
void add_study_command(CLI::App& app, const Globals& g, Action& action);
void add_ensemble_command(CLI::App& app, const Globals& g, Action& action);
void add_evaluate_command(CLI::App& app, const Globals& g, Action& action);
void add_pick_command(CLI::App& app, const Globals& g, Action& action);
void add_plant_command(CLI::App& app, const Globals& g, Action& action);

// The MPI ranks and the evaluator of a command's simulations: the run API's (api/api.hpp).
using tune::make_evaluator;
using tune::mpi_ranks;
using tune::Ranks;

// The run API's messages, logged (info and warnings) through spdlog.
tune::RunLog spdlog_log();

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

// The latest finished run of a job (api/run_directory.hpp).
using tune::latest_run_dir;

}  // namespace ftc::cli
