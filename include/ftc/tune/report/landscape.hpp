#pragma once
// The objective on a grid over two tuned parameters, evaluated as one parallel batch and drawn as
// a heatmap with a log colour scale and the optimiser's best-so-far path on top: it shows whether
// the objective can tell gains apart at all.
#include <cstdint>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "ftc/tune/evaluators/batch_evaluator.hpp"
#include "ftc/tune/job/job.hpp"
#include "ftc/tune/report/report.hpp"

namespace ftc::tune {

struct LandscapeOptions {
  int n1 = 41, n2 = 41;             // grid points per parameter
  std::vector<std::string> params;  // two tuned parameters; default: the first two of the job
  std::filesystem::path history;    // a history.csv whose best-so-far path is drawn on top
  // Values of the tuned parameters that are not plotted (default: the job's controller's), and
  // where they come from, in words ("the tuned value, out/t/gains.json" or "the job's value").
  std::vector<std::pair<std::string, double>> fixed;
  std::string fixed_source = "the job's value";
  // The run's noise floor (relative spread of the tuned objective, gains.json's noise_floor):
  // grid values within it of the lowest share one colour. 0: unknown.
  double noise_floor = 0.0;
  FigureFormat format = FigureFormat::png;
  // Called on the calling thread after each block of grid points with the points done and the
  // total (the grid is evaluated a block at a time so that progress can be shown).
  std::function<void(std::int64_t, std::int64_t)> progress;
};

struct LandscapeResult {
  std::filesystem::path csv, figure;
  std::vector<std::string> params;
  std::int64_t simulations = 0;
  double best_objective = 0.0;
  std::vector<double> best;  // grid point with the lowest objective
  // The unplotted tuned parameters and the values they were held at.
  std::vector<std::pair<std::string, double>> fixed;
  std::string fixed_source;
  // History rows drawn, and those of them that lie on the map (their unplotted parameters at
  // the fixed values); the others are drawn projected.
  int path_points = 0, path_on_map = 0;
};

// Evaluates the job's objective on a grid over two tuned parameters (one parallel batch) and
// draws it as a heatmap with a log colour scale.
LandscapeResult compute_landscape(const Job& job, const std::filesystem::path& out_dir,
                                  const LandscapeOptions& options, BatchEvaluator& evaluator);

}  // namespace ftc::tune
