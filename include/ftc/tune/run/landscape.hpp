#pragma once
// The objective on a grid over two tuned parameters, evaluated as one parallel batch a block at a
// time: whether the objective can tell gains apart at all (`ftctune landscape`). The report draws
// it (ftc/tune/report/landscape.hpp); the run API writes it (api/api.hpp's compute_landscape).
#include <cstdint>
#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "ftc/tune/evaluators/batch_evaluator.hpp"
#include "ftc/tune/job/job.hpp"

namespace ftc::tune {

struct LandscapeGrid {
  int n1 = 41, n2 = 41;             // grid points per parameter
  std::vector<std::string> params;  // two tuned parameters; default: the first two of the job
  // Values of the tuned parameters that are not plotted (default: the job's controller's), and
  // where they come from, in words ("the tuned value, out/t/gains.json" or "the job's value").
  std::vector<std::pair<std::string, double>> fixed;
  std::string fixed_source = "the job's value";
  // Called on the calling thread after each block of grid points with the points done and the
  // total (the grid is evaluated a block at a time so that progress can be shown).
  std::function<void(std::int64_t, std::int64_t)> progress;
};

struct LandscapePoint {
  double p0 = 0.0, p1 = 0.0;  // the two parameters, in the grid's order
  double objective = 0.0;     // +inf when diverged
  double fitness = 0.0;
  bool diverged = false;
};

struct Landscape {
  std::vector<std::string> params;
  std::vector<ParameterBounds> bounds;  // the two parameters'
  int n1 = 0, n2 = 0;
  std::vector<LandscapePoint> points;  // n1 rows of n2, the second parameter varying fastest
  std::int64_t simulations = 0;
  double best_objective = 0.0;
  std::vector<double> best;      // grid point with the lowest objective
  double worst_objective = 0.0;  // the largest finite objective
  double least_excess = 0.0;     // the smallest objective/best - 1 above 0 (inf: none)
  // The unplotted tuned parameters and the values they were held at.
  std::vector<std::pair<std::string, double>> fixed;
  std::string fixed_source;
};

// Evaluates the job's objective on the grid, evenly spaced in the coordinate the optimiser
// searches (the value, or its log). InputError for a job without tuning or a bad grid.
Landscape evaluate_landscape(const Job& job, const LandscapeGrid& grid, BatchEvaluator& evaluator);

// landscape.csv: the two parameters, the objective, the fitness and diverged per point, a blank
// line after each row of the grid (gnuplot's grid rows).
std::string landscape_csv(const Landscape& landscape);

}  // namespace ftc::tune
