// ftctune run JOB: tune the job's controller and write the gains file and its companions.
// The run itself (output directory, lock, staging, checkpoints, files) is the run API's
// (run/api.hpp); this prints what it did.
#include <spdlog/spdlog.h>

#include <cmath>
#include <cstdio>

#include "cli.hpp"
#include "ftc/tune/run/api.hpp"
#include "ftc/tune/run/documents.hpp"
#include "progress.hpp"

namespace ftc::cli {
namespace {

struct RunCliOptions {
  std::string job;
  std::string out;
  int threads = 0;
  std::optional<std::uint64_t> seed;
  bool report = false;
  bool baseline = false;
  bool force = false;
  bool checkpoint = false;     // after every iteration, from the first
  bool no_checkpoint = false;  // never (else: once the run looks like taking over a minute)
  bool resume = false;
};

int run_tuning(const RunCliOptions& o, const Globals& g) {
  const tune::Job job = tune::load_job(o.job);
  std::vector<std::string> names;
  if (job.tuning)
    for (const tune::ParameterBounds& b : job.tuning->parameters) names.push_back(b.name);
  tune::RunJobOptions ro;
  ro.job_file = o.job;
  ro.out = o.out;
  ro.threads = o.threads;
  ro.seed = o.seed;
  ro.baseline = o.baseline;
  ro.force = o.force;
  ro.resume = o.resume;
  ro.checkpoint = o.no_checkpoint ? tune::CheckpointPolicy::never
                  : o.checkpoint  ? tune::CheckpointPolicy::every_iteration
                                  : tune::CheckpointPolicy::automatic;
  ProgressBar bar(!g.quiet);
  const tune::RunLog log = spdlog_log();
  ro.log = [&](tune::LogLevel level, const std::string& message) {
    bar.clear();
    log(level, message);
  };
  ro.on_iteration = [&](const tune::IterationReport& it) {
    const tune::HistoryRow& h = it.row;
    bar.clear();
    spdlog::info(
        "iteration {}/{}: best J = {:.6g} ({}), {}/{} evaluations, {:.1f} s elapsed, ETA {:.1f} s",
        h.iteration, it.iterations, h.best_fitness, tune::parameters_text(names, h.best),
        h.evaluations, it.total_evaluations, it.elapsed, it.eta);
    bar.draw(h.evaluations, it.total_evaluations, it.elapsed);
    return true;
  };
  const tune::RunJobResult result = tune::run_job(job, ro);
  bar.clear();
  const tune::TuningOutcome& r = result.outcome;
  const std::filesystem::path& out = result.out;
  const double wall = result.wall_seconds;
  if (!g.quiet) {
    std::printf("tuned %s: %s\n", tune::display_name(job.controller.type).c_str(),
                tune::parameters_text(names, r.optimization.best).c_str());
    // The objective with seven digits and the change in %: J to six digits can read the same
    // while the gains and the objective move.
    const double best = r.best().outcome.evaluation.objective;
    const double base = r.baseline().outcome.evaluation.objective;
    std::printf("  %s = %.6e (job's own controller: %.6e", tune::objective_label(job).c_str(), best,
                base);
    if (std::isfinite(best) && std::isfinite(base) && base > 0)
      std::printf(", %.3g %% %s", 100 * std::abs(base - best) / base,
                  best <= base ? "lower" : "higher");
    std::printf("); fitness J = %.6g\n", r.optimization.best_fitness);
    if (r.scenarios > r.listed_scenarios)
      std::printf("  over %zu scenarios: %zu listed, %zu ensemble members; %d unrecoverable%s\n",
                  r.scenarios, r.listed_scenarios, r.scenarios - r.listed_scenarios,
                  r.unrecoverable, r.left_out > 0 ? ", left out of the objective" : "");
    if (const std::string nf = tune::noise_floor_sentence(r); !nf.empty())
      std::printf("  %s\n", nf.c_str());
    std::printf("  %lld simulations on %d thread%s in %.2f s\n",
                static_cast<long long>(r.simulations), r.threads, r.threads == 1 ? "" : "s", wall);
    std::printf(
        "  wrote %s/{gains.json, history.csv, trials.csv, comparison.json, comparison.md, "
        "job.json, run.json%s} and trajectories/\n",
        out.c_str(), o.baseline ? ", history-random.csv" : "");
  }
  const int report_status = o.report ? render_run_report(out.string(), "html", g.quiet) : 0;
  // Gains that diverge on what the objective counts must not reach a spacecraft: the files stay
  // for diagnosis (and the gains loader refuses them), and the exit status says so, --quiet or
  // not, with a code of its own (3) that scripts can tell from an internal error (1).
  if (result.diverged()) {
    std::fprintf(stderr,
                 "ftctune: error: every candidate diverged (fitness 0): %s/gains.json holds a "
                 "diverging controller and must not be deployed; narrow "
                 "tuning.parameters or check the scenarios\n",
                 out.c_str());
    return 3;
  }
  return report_status;
}

}  // namespace

void add_run_command(CLI::App& app, const Globals& g, Action& action) {
  auto opts = std::make_shared<RunCliOptions>();
  CLI::App* sub = app.add_subcommand("run", "Tune a job's controller and write the gains file");
  sub->add_option("job", opts->job, "Job file (ftctune.job/1)")->required();
  sub->add_option("--out", opts->out, "Output directory (default out/<job name>)")
      ->check(output_directory());
  sub->add_option("--threads", opts->threads, "Worker threads (default: all cores)")
      ->check(CLI::Range(0, 4096));
  sub->add_option("--seed", opts->seed, "Seed instead of the job's tuning.seed")
      ->check(seed_value());
  sub->add_flag(
      "--baseline", opts->baseline,
      "Also run random search with the same budget (history-random.csv, drawn in Fig. 5)");
  sub->add_flag("--report", opts->report, "Then draw the figures and report.html (ftctune report)");
  sub->add_flag("--force", opts->force, "Replace the run in an output directory that holds one");
  CLI::Option* checkpoint = sub->add_flag(
      "--checkpoint", opts->checkpoint,
      "Write <out>/checkpoint.json after every iteration (default: once the run looks like "
      "taking over a minute)");
  sub->add_flag("--no-checkpoint", opts->no_checkpoint, "Never write a checkpoint")
      ->excludes(checkpoint);
  sub->add_flag("--resume", opts->resume,
                "Continue the interrupted run in --out (or out/<job name>) from its checkpoint; "
                "without one, start from the first iteration")
      ->excludes("--force");
  sub->callback([&action, &g, opts] { action = [&g, opts] { return run_tuning(*opts, g); }; });
}

}  // namespace ftc::cli
