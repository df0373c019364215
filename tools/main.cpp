// ftctune: tunes fault-tolerant sliding-mode controllers offline.
// Exit codes: 0 success, 2 invalid input (one line naming the file and JSON path), 1 internal
// error.
#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>

#include <cstdio>
#include <exception>

#include "cli.hpp"
#include "ftc/sim/input_error.hpp"
#include "ftc/version.hpp"

int main(int argc, char** argv) {
  CLI::App app{"ftctune: offline tuning of fault-tolerant sliding-mode controllers"};
  app.set_version_flag("--version", std::string(ftc::kToolName) + " " + ftc::kVersion);
  app.require_subcommand(1);
  app.fallthrough();  // global flags such as -q may also follow the subcommand
  ftc::cli::Globals globals;
  app.add_flag("-q,--quiet", globals.quiet, "Only errors on stderr");

  ftc::cli::Action action;
  ftc::cli::add_run_command(app, globals, action);
  ftc::cli::add_simulate_command(app, globals, action);
  ftc::cli::add_validate_command(app, globals, action);
  ftc::cli::add_schema_command(app, globals, action);
  ftc::cli::add_report_commands(app, globals, action);
  ftc::cli::add_study_command(app, globals, action);
  ftc::cli::add_ensemble_command(app, globals, action);
  ftc::cli::add_evaluate_command(app, globals, action);
  ftc::cli::add_serve_command(app, globals, action);
  ftc::cli::add_client_commands(app, globals, action);

  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForVersion& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    std::fprintf(stderr, "ftctune: error: %s (see ftctune --help)\n", e.what());
    return 2;
  }

  auto logger = spdlog::stderr_color_mt("ftctune");
  spdlog::set_default_logger(logger);
  spdlog::set_pattern("%^[%l]%$ %v");
  spdlog::set_level(globals.quiet ? spdlog::level::err : spdlog::level::info);

  try {
    return action();
  } catch (const ftc::InputError& e) {
    std::fprintf(stderr, "ftctune: error: %s\n", e.what());
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "ftctune: internal error: %s\n", e.what());
    return 1;
  }
}
