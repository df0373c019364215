// ftctune report RUN_DIR and ftctune landscape JOB: figures engineers can look at.
#include <spdlog/spdlog.h>

#include <charconv>
#include <chrono>
#include <cstdio>

#include "cli.hpp"
#include "ftc/runtime/json_reader.hpp"
#include "ftc/sim/input_error.hpp"
#include "ftc/tune/io/files.hpp"
#include "ftc/tune/report/landscape.hpp"
#include "ftc/tune/report/report.hpp"
#include "ftc/tune/api/api.hpp"
#include "ftc/tune/run/documents.hpp"
#include "progress.hpp"

namespace ftc::cli {

int render_run_report(const std::string& dir, const std::string& format, bool quiet) {
  tune::ReportOptions ro;
  if (format == "html")
    ro.html = true;
  else if (format == "png" || format == "svg") {
    ro.html = false;
    ro.format = format == "png" ? tune::FigureFormat::png : tune::FigureFormat::svg;
  } else {
    throw InputError("--format", "", "must be html, png or svg (got \"" + format + "\")");
  }
  const auto t0 = std::chrono::steady_clock::now();
  const tune::ReportResult r = tune::render_report(dir, ro);
  const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (!quiet) {
    for (const auto& f : r.figures) std::printf("wrote %s\n", f.c_str());
    if (!r.html.empty()) std::printf("wrote %s\n", r.html.c_str());
  }
  spdlog::info("report rendered in {:.2f} s", s);
  return 0;
}

namespace {

struct LandscapeCli {
  std::string job, grid = "41x41", params, out, history, format = "png";
  int threads = 0;
  bool force = false;
  bool at_job_values = false;
};

// "N1xN2": two whole numbers and an x, nothing else ("3x3x3", "3x3junk" and "2x3.9" are not).
bool parse_grid(const std::string& text, int& n1, int& n2) {
  const char* end = text.data() + text.size();
  const auto [x, e1] = std::from_chars(text.data(), end, n1);
  if (e1 != std::errc() || x == text.data() || x == end || *x != 'x') return false;
  const auto [last, e2] = std::from_chars(x + 1, end, n2);
  return e2 == std::errc() && last != x + 1 && last == end;
}

int run_landscape(const LandscapeCli& o, const Globals& g) {
  namespace fs = std::filesystem;
  const tune::Job job = tune::load_job(o.job);
  tune::LandscapeJobOptions lo;
  if (!parse_grid(o.grid, lo.n1, lo.n2))
    throw InputError("--grid", "", "expected N1xN2, e.g. 41x41 (got \"" + o.grid + "\")");
  for (std::size_t i = 0; i < o.params.size();) {
    const std::size_t j = std::min(o.params.find(',', i), o.params.size());
    lo.params.push_back(o.params.substr(i, j - i));
    i = j + 1;
  }
  if (o.format != "png" && o.format != "svg")
    throw InputError("--format", "", "must be png or svg (got \"" + o.format + "\")");
  lo.format = o.format == "png" ? tune::FigureFormat::png : tune::FigureFormat::svg;
  lo.out = o.out;
  lo.history = o.history;
  lo.threads = o.threads;
  lo.force = o.force;
  lo.at_job_values = o.at_job_values;
  lo.log = spdlog_log();
  const auto t0 = std::chrono::steady_clock::now();
  ProgressBar bar(!g.quiet);
  int last_tenth = 0;
  lo.progress = [&](std::int64_t done, std::int64_t total) {
    const double elapsed =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    // A log line every tenth of the grid; the bar (on a terminal) after every block.
    if (const int tenth = static_cast<int>(10 * done / total); tenth > last_tenth) {
      last_tenth = tenth;
      bar.clear();
      spdlog::info("{}/{} grid points, {:.1f} s elapsed, ETA {:.1f} s", done, total, elapsed,
                   elapsed * static_cast<double>(total - done) / static_cast<double>(done));
    }
    bar.draw(done, total, elapsed);
  };
  const tune::LandscapeResult r = tune::landscape_job(job, lo).landscape;
  bar.clear();
  const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (!g.quiet) {
    std::printf(
        "%lld simulations in %.2f s; lowest on the grid: %s = %.6g at %s = %.5g, %s = "
        "%.5g\n",
        static_cast<long long>(r.simulations), s, tune::objective_label(job).c_str(),
        r.best_objective, r.params[0].c_str(), r.best[0], r.params[1].c_str(), r.best[1]);
    for (const auto& [name, value] : r.fixed)
      std::printf("  %s held fixed at %.6g (%s)\n", name.c_str(), value, r.fixed_source.c_str());
    if (r.path_points > r.path_on_map)
      std::printf("  the optimiser's path is drawn projected: %d of its %d points lie on the map\n",
                  r.path_on_map, r.path_points);
    std::printf("wrote %s and %s\n", r.csv.c_str(), r.figure.c_str());
  }
  return 0;
}

}  // namespace

void add_report_commands(CLI::App& app, const Globals& g, Action& action) {
  {
    auto dir = std::make_shared<std::string>();
    auto format = std::make_shared<std::string>("html");
    CLI::App* sub = app.add_subcommand("report", "Draw the figures and the HTML report of a run");
    sub->add_option("run_dir", *dir,
                    "Output directory of `ftctune run`, or a job file: its latest run")
        ->required();
    sub->add_option("--format", *format,
                    "html (report.html with the PNG figures inline, default), png or svg");
    sub->callback([&action, &g, dir, format] {
      action = [&g, dir, format] {
        // A job file names its latest run (out/<name>, -2, -3, ...), as for landscape.
        std::error_code ec;
        if (std::filesystem::is_regular_file(*dir, ec)) {
          const tune::Job job = tune::load_job(*dir);
          std::string why;
          const std::filesystem::path run = latest_run_dir(job, &why);
          if (run.empty())
            throw InputError(*dir, "", why + ": run `ftctune run " + *dir + "` first");
          spdlog::info("{}", why);
          return render_run_report(run.string(), *format, g.quiet);
        }
        return render_run_report(*dir, *format, g.quiet);
      };
    });
  }
  {
    auto o = std::make_shared<LandscapeCli>();
    CLI::App* sub = app.add_subcommand("landscape", "Map the objective over two tuned parameters");
    sub->add_option("job", o->job, "Job file (ftctune.job/1)")->required();
    sub->add_option("--grid", o->grid, "Grid points, N1xN2 (default 41x41)");
    sub->add_option("--params", o->params,
                    "Two tuned parameters, e.g. Kp,Ki (default: the first two)");
    sub->add_option("--out", o->out,
                    "Output directory (default <the job's latest run>/landscape, else "
                    "out/<job name>/landscape)");
    sub->add_option("--history", o->history,
                    "history.csv whose best-so-far path is drawn (default: the latest run's, "
                    "out/<job name>[-N]/history.csv, if there is one)");
    sub->add_option("--threads", o->threads, "Worker threads (default: all cores)")
        ->check(CLI::Range(0, 4096));
    sub->add_option("--format", o->format, "png (default) or svg");
    sub->add_flag("--force", o->force, "Replace the landscape the --out directory holds");
    sub->add_flag("--at-job-values", o->at_job_values,
                  "Hold the unplotted tuned parameters at the job's values instead of the latest "
                  "run's tuned ones");
    sub->callback([&action, &g, o] { action = [&g, o] { return run_landscape(*o, g); }; });
  }
}

}  // namespace ftc::cli
