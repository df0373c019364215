#pragma once
// Reports engineers can look at, drawn with gnuplot (Debian package gnuplot-nox) from the files
// a run writes:
//   fig3-attitude    x1..x3 of every compared controller against time, fault onsets marked
//   fig4-rates       x4..x6 likewise
//   fig5-fitness     the optimiser's best fitness per iteration (and random search, if present)
//   fig6-inputs      commanded outputs u_d1..u_d4 per controller, applied outputs of faulted
//   actuators fig7-fault-zoom  ‖X1‖ on a log scale over the faulted part of the run
// and report.html, one self-contained page with the figures inline, the comparison table, the
// tuned gains, the job and the run metadata.
#include <filesystem>
#include <string>
#include <vector>

#include "ftc/tune/evaluators/batch_evaluator.hpp"
#include "ftc/tune/job/job.hpp"

namespace ftc::tune {

enum class FigureFormat { png, svg };

struct ReportOptions {
  bool html = true;                         // write report.html with the figures inline as PNG
  FigureFormat format = FigureFormat::png;  // of the figure files when html is false
};

struct ReportResult {
  std::vector<std::filesystem::path> figures;  // in figures/
  std::filesystem::path html;                  // empty when not asked for
};

// Throws InputError (source: the run directory or the offending file) when the directory is not
// a complete `ftctune run` output; std::runtime_error when gnuplot is missing or fails.
ReportResult render_report(const std::filesystem::path& run_dir, const ReportOptions& options = {});

struct LandscapeOptions {
  int n1 = 41, n2 = 41;             // grid points per parameter
  std::vector<std::string> params;  // two tuned parameters; default: the first two of the job
  std::filesystem::path history;  // a history.csv whose best-so-far path is drawn on top
  FigureFormat format = FigureFormat::png;
};

struct LandscapeResult {
  std::filesystem::path csv, figure;
  std::vector<std::string> params;
  std::int64_t simulations = 0;
  double best_objective = 0.0;
  std::vector<double> best;  // grid point with the lowest objective
};

// Evaluates the job's objective on a grid over two tuned parameters (one parallel batch) and
// draws it as a heatmap with a log colour scale.
LandscapeResult compute_landscape(const Job& job, const std::filesystem::path& out_dir,
                                  const LandscapeOptions& options, BatchEvaluator& evaluator);

// One algorithm's results in a comparison: the best objective of each run (one per seed).
struct StudySeries {
  std::string label;
  std::vector<double> objectives;  // +inf for a run whose every candidate diverged
};

// Draws `dir`/study.png (or .svg) from `dir`/study.gp: one point per run for each algorithm, in
// the order given (best median first keeps the key clear of the points), with each algorithm's
// median marked; the objective axis is logarithmic when the finite objectives span a factor of
// 10 or more. Returns the figure's path.
std::filesystem::path draw_study(const std::filesystem::path& dir, const std::string& title,
                                 const std::string& objective_label,
                                 const std::vector<StudySeries>& series,
                                 FigureFormat format = FigureFormat::png);

// Runs `gnuplot script` in `dir`; throws std::runtime_error with gnuplot's message on failure.
void run_gnuplot(const std::filesystem::path& dir, const std::string& script_name);

}  // namespace ftc::tune
