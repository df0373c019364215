// ftctune validate JOB: check a job file and say what running it would cost.
#include <cstdio>

#include "cli.hpp"
#include "ftc/sim/input_error.hpp"
#include "ftc/tune/job/ensemble.hpp"

namespace ftc::cli {
namespace {

int run_validate(const std::string& file, const Globals& g) {
  try {
    const tune::Job job = tune::load_job(file);
    const std::int64_t evals = job.tuning ? job.tuning->algorithm->evaluations() : 1;
    const std::int64_t steps = job.steps_per_evaluation();
    const std::string members = job.ensemble
                                    ? " (" + std::to_string(job.scenarios.size()) + " listed + " +
                                          std::to_string(job.ensemble->count) + " ensemble members)"
                                    : "";
    if (!g.quiet)
      std::printf(
          "%s: valid job \"%s\": %lld evaluation%s x %zu scenario%s%s, %lld simulated steps "
          "per evaluation, %.3g in all%s\n",
          file.c_str(), job.name.c_str(), static_cast<long long>(evals), evals == 1 ? "" : "s",
          job.scenario_count(), job.scenario_count() == 1 ? "" : "s", members.c_str(),
          static_cast<long long>(steps), static_cast<double>(evals) * static_cast<double>(steps),
          job.tuning ? "" : " (no tuning section: simulate only)");
    return 0;
  } catch (const InputError& e) {
    std::fprintf(stderr, "ftctune: error: %s: %zu problem%s\n", e.source().c_str(),
                 e.errors().size(), e.errors().size() == 1 ? "" : "s");
    for (const FieldError& fe : e.errors()) std::fprintf(stderr, "  %s\n", to_string(fe).c_str());
    return 2;
  }
}

}  // namespace

void add_validate_command(CLI::App& app, const Globals& g, Action& action) {
  auto file = std::make_shared<std::string>();
  CLI::App* sub = app.add_subcommand("validate", "Check a job file and list every problem");
  sub->add_option("job", *file, "Job file (ftctune.job/1)")->required();
  sub->callback([&action, &g, file] { action = [&g, file] { return run_validate(*file, g); }; });
}

}  // namespace ftc::cli
