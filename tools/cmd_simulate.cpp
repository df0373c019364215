// ftctune simulate JOB: closed-loop simulation of one controller on every scenario of a job.
#include <spdlog/spdlog.h>

#include <cmath>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <string>

#include "cli.hpp"
#include "ftc/runtime/controller_json.hpp"
#include "ftc/runtime/gains.hpp"
#include "ftc/sim/controllers.hpp"
#include "ftc/sim/input_error.hpp"
#include "ftc/sim/metrics_record.hpp"
#include "ftc/tune/api/api.hpp"
#include "ftc/tune/problem/problem.hpp"
#include "ftc/tune/run/documents.hpp"
#include "ftc/tune/run/tuning_run.hpp"
#include "ftc/version.hpp"

namespace ftc::cli {
namespace {

using nlohmann::json;

struct SimulateOptions {
  std::string job;
  std::string controller;
  std::vector<std::string> sets;
  std::string gains;
  std::string out;
  double record_interval = 0.01;
  bool json_output = false;  // --json: one JSON document of what was simulated on stdout
};

std::string fmt(double v, const char* f = "%.4g") {
  if (!std::isfinite(v)) return "inf";
  char buf[32];
  std::snprintf(buf, sizeof buf, f, v);
  return buf;
}

int run_simulate(const SimulateOptions& o, const Globals& g) {
  const tune::Job job = tune::load_job(o.job);
  sim::ControllerConfig controller;
  if (!o.gains.empty()) {
    if (!o.controller.empty() || !o.sets.empty())
      throw InputError("--gains", "", "cannot be combined with --controller or --set");
    const runtime::Gains gains = runtime::read_gains(o.gains);
    for (const sim::Scenario& s : job.scenarios) runtime::check_sample_time(gains, s.sample_time);
    // Replaying gains on other scenarios is a fair question, so another job is only a warning:
    // the metrics are then not the objective the gains were tuned to.
    try {
      runtime::check_job(gains, tune::canonical_job_sha256(job));
    } catch (const InputError& e) {
      spdlog::warn("{}: the metrics below are not the objective they were tuned to", e.what());
    }
    controller = gains.controller;
  } else {
    controller = select_controller(job, o.controller, o.sets);
  }
  tune::SimulateJobOptions so;
  so.record_every = o.record_interval;
  so.out = o.out;  // empty: a folder of its own, beside a run's files, never over them
  const tune::SimulateJobResult r = tune::simulate_job(job, controller, so);
  for (const std::string& w : r.warnings) spdlog::warn("{}", w);
  const tune::Evaluation& e = r.evaluation;
  if (o.json_output) {
    // metrics.json's content, with where it and the trajectories went.
    json printed = r.document;
    printed["command"] = "simulate";
    printed["out"] = r.out.string();
    json files = json::array();
    for (const auto& t : r.trajectories) files.push_back(t.first);
    files.push_back("metrics.json");
    printed["files"] = files;
    printed["objective_label"] = tune::objective_label(job);
    std::printf("%s\n", printed.dump(2).c_str());
    return 0;
  }

  if (!g.quiet) {
    std::printf(
        "%s on job %s (%s in window [%s, %s) s, %s over %zu scenario%s)\n",
        sim::to_string(controller.type), job.name.c_str(),
        std::string(job.objective.metric->name).c_str(), fmt(job.objective.window.t0).c_str(),
        std::isfinite(job.objective.window.t1) ? fmt(job.objective.window.t1).c_str() : "end",
        tune::to_string(job.objective.aggregate), e.scenarios.size(),
        e.scenarios.size() == 1 ? "" : "s");
    // The window and run fields of the metrics record (ftc/sim/metrics_record.hpp) in its
    // order (those of its tables); metrics.json has every field.
    std::printf("  %-16s", "scenario");
    for (const sim::MetricField& f : sim::kMetricFields)
      if (f.in_tables && f.scope != sim::MetricScope::fault)
        std::printf(" %12s", std::string(f.name).c_str());
    std::printf("  diverged\n");
    for (std::size_t i = 0; i < e.scenarios.size(); ++i) {
      const sim::MetricValues m = sim::MetricValues::of(e.scenarios[i]);
      std::printf("  %-16s", job.scenarios[i].name.c_str());
      for (std::size_t f = 0; f < sim::kMetricFieldCount; ++f)
        if (sim::kMetricFields[f].in_tables &&
            sim::kMetricFields[f].scope != sim::MetricScope::fault)
          std::printf(" %12s", fmt(m.field(f)[0]).c_str());
      std::printf("  %s%s\n", e.scenarios[i].diverged ? "yes" : "no",
                  r.document["scenarios"][i]["recoverable"].get<bool>() ? "" : "  unrecoverable");
    }
    if (r.counted > 0)
      std::printf("  objective %s, fitness J = %s\n", fmt(e.objective, "%.6g").c_str(),
                  fmt(e.fitness, "%.6g").c_str());
    else
      std::printf("  no objective: every scenario is unrecoverable, and the objective leaves "
                  "those out\n");
    std::printf("  wrote %s and trajectory CSV\n", (r.out / "metrics.json").c_str());
  }
  return 0;
}

}  // namespace

void add_simulate_command(CLI::App& app, const Globals& g, Action& action) {
  auto opts = std::make_shared<SimulateOptions>();
  CLI::App* sub =
      app.add_subcommand("simulate", "Simulate a controller on every scenario of a job");
  sub->add_option("job", opts->job, "Job file (ftctune.job/1)")->required();
  sub->add_option("--controller", opts->controller,
                  "Controller type with its Table 1 defaults instead of the job's controller (" +
                      std::string(sim::controller_type_list()) + ")");
  // One value per --set, so the job path may come after them.
  sub->add_option("--set", opts->sets, "Override a controller parameter, KEY=VALUE (repeatable)")
      ->allow_extra_args(false);
  sub->add_option("--gains", opts->gains,
                  "Simulate the controller of a gains file (ftctune.gains/1)");
  sub->add_option("--out", opts->out, "Output directory (default out/<job name>/simulate)")
      ->check(output_directory());
  sub->add_option("--record-every", opts->record_interval,
                  "Trajectory sampling interval in seconds (default 0.01)");
  sub->add_flag("--json", opts->json_output,
                "Print what was simulated as one JSON document on standard output (metrics.json's "
                "content, the output directory and its files)");
  sub->callback([&action, &g, opts] { action = [&g, opts] { return run_simulate(*opts, g); }; });
}

}  // namespace ftc::cli
