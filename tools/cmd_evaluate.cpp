// ftctune evaluate JOB --gains FILE...: out-of-sample validation of tuned gains on the job's
// scenarios and on ensemble members drawn with a seed they were not tuned on.
#include <spdlog/spdlog.h>

#include <chrono>
#include <cstdio>
#include <nlohmann/json.hpp>

#include "cli.hpp"
#include "ftc/runtime/json_reader.hpp"
#include "ftc/sim/input_error.hpp"
#include "ftc/tune/job/ensemble.hpp"
#include "ftc/tune/report/evaluation.hpp"
#include "ftc/tune/api/api.hpp"
#include "ftc/tune/run/documents.hpp"
#include "ftc/tune/run/evaluate.hpp"
#include "progress.hpp"

namespace ftc::cli {
namespace {

struct EvaluateCliOptions {
  std::string job;
  std::vector<std::string> gains;
  std::string front;  // --front RUN_DIR
  std::optional<std::uint64_t> seed;
  std::optional<std::int64_t> count;
  std::string out;
  int threads = 0;
  bool no_figure = false;
  bool json_output = false;  // --json: one JSON document of what was evaluated on stdout
};

int run_evaluate(const EvaluateCliOptions& o, const Globals& g) {
  namespace fs = std::filesystem;
  const tune::Job job = tune::load_job(o.job);
  tune::EvaluateJobOptions options;
  // LABEL=FILE names the controller in tables and figures; a bare FILE is labelled by its path.
  for (const std::string& p : o.gains) {
    const std::size_t eq = p.find('=');
    if (eq == std::string::npos)
      options.gains.push_back({p, ""});
    else if (eq == 0 || eq + 1 == p.size())
      throw InputError("--gains", "", "\"" + p + "\": expected FILE or LABEL=FILE");
    else
      options.gains.push_back({p.substr(eq + 1), p.substr(0, eq)});
  }
  options.seed = o.seed;
  options.count = o.count;
  options.figure = !o.no_figure;
  options.threads = o.threads;
  options.front = o.front;
  options.log = spdlog_log();
  // Beside the job's latest run (out/<name>, or -2, -3, ... where `run` moved on), whose report
  // then shows it.
  options.out = o.out.empty() ? tune::evaluation_dir(job, options.log) : fs::path(o.out);
  // Under --json standard output carries the document only (logs go to standard error).
  const bool quiet = g.quiet || o.json_output;
  if (!quiet && job.ensemble)
    std::printf(
        "Evaluating on %s: %zu listed scenario%s + %lld ensemble members, held-out "
        "seed %llu%s\n",
        job.name.c_str(), job.scenarios.size(), job.scenarios.size() == 1 ? "" : "s",
        static_cast<long long>(o.count.value_or(job.ensemble->count)),
        static_cast<unsigned long long>(o.seed.value_or(job.ensemble->seed + 1)),
        o.seed ? "" : " (the job's seed + 1)");
  ProgressBar bar(!g.quiet);
  const auto start = std::chrono::steady_clock::now();
  const auto elapsed = [&] {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  };
  options.progress = [&](std::int64_t done, std::int64_t total) {
    bar.draw(done, total, elapsed());
  };
  const tune::EvaluateJobResult result = tune::evaluate_job(job, options);
  bar.clear();
  const tune::EvaluationResult& r = result.evaluation;
  const fs::path& out = result.out;
  const fs::path& figure = result.figure;
  if (o.json_output) {
    using nlohmann::json;
    json files = {"evaluation.json", "evaluation.csv"};
    if (!figure.empty()) {
      files.push_back("evaluation.gp");  // the figure's gnuplot script, beside it
      files.push_back(figure.filename().string());
    }
    files.push_back("worst");
    if (result.front) files.push_back("front.json");
    if (!result.front_figure.empty()) {
      files.push_back("front-held-out.gp");
      files.push_back(result.front_figure.filename().string());
    }
    json controllers = json::array();
    for (const tune::EvaluatedController& c : r.controllers)
      controllers.push_back({{"label", c.label},
                             {"source", c.source},
                             {"aggregates", tune::summary_json(c.aggregates)}});
    const json doc = {{"command", "evaluate"},
                      {"job", job.name},
                      {"out", out.string()},
                      {"files", files},
                      {"evaluation", (out / "evaluation.json").string()},
                      {"seed", r.seed},
                      {"count", r.count},
                      {"listed_scenarios", job.scenarios.size()},
                      {"objective_label", tune::objective_label(job)},
                      {"controllers", controllers},
                      {"simulations", r.simulations},
                      {"threads", result.threads},
                      {"wall_seconds", elapsed()}};
    json with_front = doc;
    if (result.front) {
      std::size_t on = 0;
      for (const tune::FrontPoint& p : result.front->points) on += p.dominated ? 0 : 1;
      with_front["front"] = {
          {"points", result.front->points.size()},
          {"on_front", on},
          {"hypervolume", json_io::json_number(result.front->hypervolume)},
          {"in_sample_hypervolume",
           json_io::json_number(result.front->held_out->in_sample_hypervolume)},
          {"knee", on > 0 ? json(result.front->picked) : json()}};
    }
    std::printf("%s\n", with_front.dump(2).c_str());
    return 0;
  }
  if (g.quiet) return 0;
  const tune::Summary& s0 = r.controllers.front().aggregates;
  std::printf(
      "%s of each scenario over the window; %d scenario%s, %d counted, %d unrecoverable%s\n",
      std::string(job.objective.metric->name).c_str(), s0.scenarios, s0.scenarios == 1 ? "" : "s",
      s0.counted, s0.unrecoverable, s0.counted < s0.scenarios ? " (left out)" : "");
  std::fputs(tune::evaluation_table(r).c_str(), stdout);
  std::printf("  %lld simulations on %d thread%s in %.2f s\n",
              static_cast<long long>(r.simulations), result.threads, result.threads == 1 ? "" : "s",
              elapsed());
  std::printf(
      "  wrote %s/{evaluation.json, evaluation.csv%s%s%s, worst/}\n", out.c_str(),
      figure.empty() ? "" : (", " + figure.filename().string()).c_str(),
      result.front ? ", front.json" : "",
      result.front_figure.empty() ? "" : (", " + result.front_figure.filename().string()).c_str());
  if (result.front) std::fputs(tune::front_summary(job, *result.front, out).c_str(), stdout);
  return 0;
}

}  // namespace

void add_evaluate_command(CLI::App& app, const Globals& g, Action& action) {
  auto opts = std::make_shared<EvaluateCliOptions>();
  CLI::App* sub = app.add_subcommand(
      "evaluate",
      "Judge controllers out of sample: the job's own, its compare list and gains files");
  sub->add_option("job", opts->job, "Job file (ftctune.job/1)")->required();
  // One value per --gains, so the job path may come after them.
  sub->add_option("--gains", opts->gains,
                  "A gains file to evaluate, FILE or LABEL=FILE (repeatable)")
      ->allow_extra_args(false);
  sub->add_option("--seed", opts->seed,
                  "Ensemble seed of the held-out members (default: the job's seed + 1)")
      ->check(seed_value());
  sub->add_option("--count", opts->count, "Ensemble members (default: the job's count)");
  sub->add_option("--out", opts->out,
                  "Output directory (default <the job's latest run>/evaluation, else "
                  "out/<job name>/evaluation)")
      ->check(output_directory());
  sub->add_option("--threads", opts->threads, "Worker threads (default: all cores)")
      ->check(CLI::Range(0, 4096));
  sub->add_option("--front", opts->front,
                  "A run directory of the job with a front (front.json): evaluate every point "
                  "too, and write the held-out front to OUT/front.json (ftctune pick OUT picks "
                  "on it)")
      ->check(CLI::ExistingDirectory);
  // A plain flag: CLI11 shows a negated one's default in the help ("--no-figure{false}").
  sub->add_flag("--no-figure", opts->no_figure, "Skip the figure (no gnuplot needed)");
  sub->add_flag("--json", opts->json_output,
                "Print what was evaluated as one JSON document on standard output (files, "
                "each controller's aggregates); logs stay on standard error");
  sub->footer(
      "\nExamples:\n"
      "  ftctune evaluate jobs/robust-faults.json --gains out/robust-faults/gains.json\n"
      "  ftctune evaluate jobs/robust-faults.json --gains 'nominal=out/table1/gains.json' \\\n"
      "      --gains 'robust=out/robust-faults/gains.json' --count 1000\n"
      "  ftctune simulate out/robust-faults/evaluation/worst/<NN-controller>/1-<member>.json");
  sub->callback([&action, &g, opts] { action = [&g, opts] { return run_evaluate(*opts, g); }; });
}

}  // namespace ftc::cli
