// ftctune run JOB: tune the job's controller and write the gains file and its companions.
// The run itself (output directory, lock, staging, checkpoints, files) is the run API's
// (api/api.hpp); this prints what it did.
#include <spdlog/spdlog.h>

#include <cmath>
#include <cstdio>
#include <nlohmann/json.hpp>

#include "cli.hpp"
#include "ftc/runtime/json_reader.hpp"
#include "ftc/tune/api/api.hpp"
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
  bool no_capping = false;  // evaluate every candidate on every scenario (issue 27)
  bool no_cache = false;    // simulate a decision vector again when it comes again (issue 43)
  bool force = false;
  bool checkpoint = false;     // after every iteration, from the first
  bool no_checkpoint = false;  // never (else: once the run looks like taking over a minute)
  bool resume = false;
  bool json_output = false;  // --json: one JSON document of what the run did on stdout
  bool strict = false;       // --strict: a run with warnings exits 4
};

// What `run --json` prints: where the files went and what the run found.
nlohmann::json run_document(const tune::Job& job, const tune::RunJobResult& result,
                            const std::vector<std::string>& names, const std::string& report) {
  using nlohmann::json;
  const tune::TuningOutcome& r = result.outcome;
  json tuned = json::object();
  for (std::size_t i = 0; i < names.size() && i < r.optimization.best.size(); ++i)
    tuned[names[i]] = r.optimization.best[i];
  json doc;
  doc["command"] = "run";
  doc["job"] = job.name;
  doc["out"] = result.out.string();
  doc["gains"] = (result.out / "gains.json").string();
  doc["files"] = result.files;
  if (!report.empty()) doc["report"] = report;
  doc["controller"] = sim::to_string(job.controller.type);
  doc["tuned"] = tuned;
  doc["objective_label"] = tune::objective_label(job);
  doc["objective"] = json_io::json_number(r.best().outcome.evaluation.objective);
  doc["baseline_objective"] = json_io::json_number(r.baseline().outcome.evaluation.objective);
  doc["fitness"] = r.optimization.best_fitness;
  doc["diverged"] = result.diverged();
  doc["scenarios"] = r.scenarios;
  doc["listed_scenarios"] = r.listed_scenarios;
  doc["unrecoverable"] = r.unrecoverable;
  doc["noise_floor"] =
      r.noise_floor ? json_io::json_number(r.noise_floor->relative_spread) : json(nullptr);
  doc["warnings"] = r.warnings;
  doc["simulations"] = r.simulations;
  doc["threads"] = r.threads;
  doc["wall_seconds"] = result.wall_seconds;
  return doc;
}

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
  ro.capping = !o.no_capping;
  ro.cache = !o.no_cache;
  ro.force = o.force;
  ro.resume = o.resume;
  ro.checkpoint = o.no_checkpoint ? tune::CheckpointPolicy::never
                  : o.checkpoint  ? tune::CheckpointPolicy::every_iteration
                                  : tune::CheckpointPolicy::automatic;
  // Under --json standard output carries the document only (logs go to standard error).
  const bool quiet = g.quiet || o.json_output;
  ProgressBar bar(!g.quiet);
  const tune::RunLog log = spdlog_log();
  ro.log = [&](tune::LogLevel level, const std::string& message) {
    bar.clear();
    log(level, message);
  };
  ro.on_iteration = [&](const tune::IterationReport& it) {
    const tune::HistoryRow& h = it.row;
    bar.clear();
    // A front has no single best: its size so far, not a J that names one corner of it.
    if (it.front_points)
      spdlog::info(
          "iteration {}/{}: front of {} point{} so far, {}/{} evaluations, {:.1f} s elapsed, ETA "
          "{:.1f} s",
          h.iteration, it.iterations, *it.front_points, *it.front_points == 1 ? "" : "s",
          h.evaluations, it.total_evaluations, it.elapsed, it.eta);
    else
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
  if (!quiet) {
    // The documents' summary, as `submit --wait` prints a run of the service.
    std::fputs(tune::run_summary(tune::gains_document(r), tune::comparison_document(r),
                                 nlohmann::json::parse(result.run_json))
                   .c_str(),
               stdout);
    // The files as run.json lists them (front.json and front.csv for a front), the
    // trajectories as their folder.
    std::string listed;
    bool trajectories = false;
    for (const std::string& f : result.files) {
      if (f.rfind("trajectories/", 0) == 0) {
        trajectories = true;
        continue;
      }
      listed += (listed.empty() ? "" : ", ") + f;
    }
    std::printf("  wrote %s/{%s}%s\n", out.c_str(), listed.c_str(),
                trajectories ? " and trajectories/" : "");
    if (r.front) std::fputs(tune::front_summary(r.job, *r.front, out).c_str(), stdout);
  }
  const int report_status = o.report ? render_run_report(out.string(), "html", quiet) : 0;
  if (o.json_output)
    std::printf("%s\n", run_document(job, result, names,
                                     o.report ? (out / "report.html").string() : std::string())
                            .dump(2)
                            .c_str());
  // Gains that diverge on what the objective counts must not reach a spacecraft: the files stay
  // for diagnosis (and the gains loader refuses them), and the exit status says so, --quiet or
  // not, with a code of its own (3) that scripts can tell from an internal error (1).
  if (result.infeasible()) {
    std::fprintf(stderr,
                 "ftctune: error: no candidate met the job's hard goals (total violation %.6g, "
                 "see trials.csv): %s/gains.json must not be deployed; relax an at_most or "
                 "widen tuning.parameters\n",
                 r.best().outcome.evaluation.violation, out.c_str());
    return 3;
  }
  if (result.diverged()) {
    std::fprintf(stderr,
                 "ftctune: error: every candidate diverged (fitness 0): %s/gains.json holds a "
                 "diverging controller and must not be deployed; narrow "
                 "tuning.parameters or check the scenarios\n",
                 out.c_str());
    return 3;
  }
  // The files are written and may be fine to use; a script that wants no doubt asks --strict.
  if (o.strict && !r.warnings.empty()) {
    std::fprintf(stderr,
                 "ftctune: error: --strict: the run gave %zu warning%s (gains.json lists them): "
                 "check them before using %s/gains.json\n",
                 r.warnings.size(), r.warnings.size() == 1 ? "" : "s", out.c_str());
    return 4;
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
  sub->add_flag("--no-capping", opts->no_capping,
                "Simulate every candidate on every scenario (default: stop a candidate once it "
                "cannot change the search; the same gains and history, trials.csv marks it)");
  sub->add_flag("--no-cache", opts->no_cache,
                "Simulate a candidate again when the search proposes the same parameter values "
                "again (default: take its earlier results; the same gains, history and front, "
                "trials.csv marks the rows served so)");
  sub->add_flag("--report", opts->report, "Then draw the figures and report.html (ftctune report)");
  sub->add_flag("--strict", opts->strict,
                "Exit 4 when the run gives warnings (a failed or drifting loop, a parameter on its "
                "bound, a win inside the noise floor, ...); the files are written all the same");
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
  sub->add_flag("--json", opts->json_output,
                "Print what the run did as one JSON document on standard output (files, tuned "
                "values, objective, warnings); logs stay on standard error");
  sub->callback([&action, &g, opts] { action = [&g, opts] { return run_tuning(*opts, g); }; });
}

}  // namespace ftc::cli
