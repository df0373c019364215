// ftctune: tunes fault-tolerant sliding-mode controllers offline.
// Exit codes: 0 success, 2 invalid input (one line naming the file and JSON path) or a path that
// cannot be written (a full disk too), 3 a run whose every candidate diverged, 1 internal error.
#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <exception>
#include <filesystem>
#include <iostream>
#include <map>
#include <new>
#include <string>

#include "cli.hpp"
#include "ftc/sim/input_error.hpp"
#include "ftc/sim/isa.hpp"
#include "ftc/sim/plant_plugin.hpp"
#include "ftc/tune/io/files.hpp"
#include "ftc/version.hpp"

namespace {

// Two or three examples at the end of each command's --help, for commands that do not give
// their own.
const std::map<std::string, std::string> kExamples = {
    {"run",
     "  ftctune run jobs/table1.json\n  ftctune run jobs/post-fault.json --threads 2 --report\n"
     "  ftctune run jobs/table1.json --seed 7 --out out/seed7"},
    {"simulate",
     "  ftctune simulate jobs/table1.json\n  ftctune simulate --set Kp=12 --set Ki=3 "
     "jobs/table1.json\n  ftctune simulate jobs/table1.json --gains out/table1/gains.json"},
    {"validate", "  ftctune validate jobs/table1.json\n  ftctune validate my-job.json"},
    {"report", "  ftctune report out/table1\n  ftctune report out/table1 --format svg"},
    {"landscape",
     "  ftctune landscape jobs/table1.json\n  ftctune landscape jobs/robust-faults.json "
     "--params switching_gain,Kp --grid 21x21"},
    {"study",
     "  ftctune study jobs/post-fault.json --algorithms bat,random,pagmo:cmaes --seeds 1-10 "
     "--budget 110"},
    {"serve", "  ftctune serve\n  ftctune serve --bind 0.0.0.0 --port 8080 --token-file token.txt"},
    {"submit", "  ftctune submit jobs/table1.json\n  ftctune submit jobs/table1.json --wait"},
    {"status", "  ftctune status 3f9c0a7d12e4b6a1\n  ftctune status 3f9c0a7d12e4b6a1 --json"},
    {"fetch", "  ftctune fetch 3f9c0a7d12e4b6a1\n  ftctune fetch 3f9c0a7d12e4b6a1 -o gains.json"},
    {"cancel", "  ftctune cancel 3f9c0a7d12e4b6a1"},
    {"jobs",
     "  ftctune jobs\n  ftctune jobs --status running --limit 5\n  ftctune jobs --prune 30"},
    {"delete", "  ftctune delete 3f9c0a7d12e4b6a1"},
    {"help", "  ftctune help\n  ftctune help simulate"},
    {"plant",
     "  ftctune plant check build/ftctune_plant_reaction_wheel_pendulum.so\n"
     "  ftctune plant check ftctune_plant_NAME.so --against model.py"},
};

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"ftctune: offline tuning of fault-tolerant sliding-mode controllers"};
  app.name("ftctune");  // usage lines show the command, not the path it was run by
  // The SIMD instruction set of the batch simulator, chosen once (FTCTUNE_ISA overrides it).
  ftc::sim::Isa isa{};
  try {
    isa = ftc::sim::active_isa();
  } catch (const ftc::InputError& e) {
    std::fprintf(stderr, "ftctune: error: %s\n", e.what());
    return 2;
  }
  app.set_version_flag("--version", std::string(ftc::kToolName) + " " + ftc::kVersion +
                                        "\nsimulation lanes: " + ftc::sim::to_string(isa) + " (" +
                                        std::to_string(ftc::sim::lane_width(isa)) +
                                        " per core; FTCTUNE_ISA chooses)");
  app.require_subcommand(1);
  app.fallthrough();  // global flags such as -q may also follow the subcommand
  ftc::cli::Globals globals;
  app.add_flag("-q,--quiet", globals.quiet, "Only errors on stderr");
  app.add_flag("-v,--verbose", globals.verbose,
               "More detail on stderr; under mpirun, every rank logs (else rank 0 only)");

  app.add_option("--plant-path", globals.plant_path,
                 "A directory of plant plugins (ftctune_plant_NAME.so) for the jobs that name "
                 "plugin:NAME, searched before FTCTUNE_PLANT_PATH's; repeatable")
      ->type_name("DIR");

  ftc::cli::Action action;
  ftc::cli::add_run_command(app, globals, action);
  ftc::cli::add_simulate_command(app, globals, action);
  ftc::cli::add_validate_command(app, globals, action);
  ftc::cli::add_schema_command(app, globals, action);
  ftc::cli::add_report_commands(app, globals, action);
  ftc::cli::add_study_command(app, globals, action);
  ftc::cli::add_ensemble_command(app, globals, action);
  ftc::cli::add_evaluate_command(app, globals, action);
  ftc::cli::add_pick_command(app, globals, action);
  ftc::cli::add_plant_command(app, globals, action);
  ftc::cli::add_serve_command(app, globals, action);
  ftc::cli::add_client_commands(app, globals, action);

  // `ftctune help [COMMAND]`: the same text as --help.
  auto help_topic = std::make_shared<std::string>();
  CLI::App* help = app.add_subcommand("help", "Show the help of ftctune or of one command");
  help->add_option("command", *help_topic, "A command");
  help->callback([&app, &action, help_topic] {
    action = [&app, help_topic] {
      if (help_topic->empty()) {
        std::fputs(app.help().c_str(), stdout);
        return 0;
      }
      for (CLI::App* sub : app.get_subcommands({}))
        if (sub->get_name() == *help_topic) {
          std::fputs(sub->help("ftctune").c_str(), stdout);
          return 0;
        }
      std::fprintf(stderr, "ftctune: error: no command \"%s\" (see ftctune --help)\n",
                   help_topic->c_str());
      return 2;
    };
  });
  for (CLI::App* sub : app.get_subcommands({}))
    if (sub->get_footer().empty())
      if (const auto it = kExamples.find(sub->get_name()); it != kExamples.end())
        sub->footer("\nExamples:\n" + it->second);

  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForVersion& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    // Point to the help of the command being parsed, when there is one.
    std::string where = "ftctune --help";
    for (const CLI::App* sub : app.get_subcommands())
      where = "ftctune " + sub->get_name() + " --help";
    std::fprintf(stderr, "ftctune: error: %s (see %s)\n", e.what(), where.c_str());
    return 2;
  }

  {
    std::vector<std::filesystem::path> dirs(globals.plant_path.begin(), globals.plant_path.end());
    ftc::sim::set_plant_search_path(std::move(dirs));
  }
  // A server's plugins, on every rank (under mpirun the other ranks never run the service, but
  // they simulate its jobs): loaded now, and then no library by name.
  if (!globals.plugins.empty()) try {
      for (const std::string& lib : globals.plugins) ftc::sim::load_plant_plugin(lib);
      ftc::sim::lock_plant_plugins();
    } catch (const ftc::InputError& e) {
      std::fprintf(stderr, "ftctune: error: %s\n", e.what());
      return 2;
    }

  auto logger = spdlog::stderr_color_mt("ftctune");
  spdlog::set_default_logger(logger);
  spdlog::set_pattern("%^[%l]%$ %v");
  spdlog::set_level(globals.quiet     ? spdlog::level::err
                    : globals.verbose ? spdlog::level::debug
                                      : spdlog::level::info);

  // Under mpirun every rank parsed the same command line; rank 0 runs it, the others simulate
  // for it (and log nothing unless --verbose).
  ftc::cli::Ranks ranks(argc, argv);
  if (ranks.failed()) return 2;
  if (!ranks.leader()) {
    if (!globals.verbose) spdlog::set_level(spdlog::level::off);
    return ranks.serve();
  }

  try {
    const int rc = action();
    // What went to standard output must have arrived: a full disk or a closed pipe behind it
    // (`ftctune schema job > /dev/full`) is an error, not exit 0 with the output lost.
    errno = 0;
    std::cout.flush();
    if (std::fflush(stdout) != 0 || std::ferror(stdout) || !std::cout) {
      const int error = errno;
      std::fprintf(stderr, "ftctune: error: cannot write to standard output%s%s\n",
                   error ? ": " : " (a full disk or a closed pipe behind it?)",
                   error ? std::strerror(error) : "");
      return 2;
    }
    return rc;
  } catch (const std::bad_alloc&) {
    // An allocation the machine cannot give: a clean error, never an abort. What a job needs
    // is checked against its budget up front (see docs/reliability.md); this is the backstop.
    std::fprintf(stderr,
                 "ftctune: error: out of memory: the job needs more memory than this machine "
                 "can give; make it smaller (fewer ensemble members or scenarios)\n");
    return 2;
  } catch (const ftc::InputError& e) {
    std::fprintf(stderr, "ftctune: error: %s\n", e.what());
    return 2;
  } catch (const std::filesystem::filesystem_error& e) {
    // A path the user gave or the machine's state (a file where a directory should be, no
    // permission, a full disk), not a defect of ftctune.
    std::fprintf(stderr, "ftctune: error: %s\n", e.what());
    return 2;
  } catch (const ftc::tune::OutputError& e) {
    // An output that could not be written whole (a target that is not a regular file, gnuplot's
    // failure): nothing was put in its place.
    std::fprintf(stderr, "ftctune: error: %s\n", e.what());
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "ftctune: internal error: %s\n", e.what());
    return 1;
  }
}
