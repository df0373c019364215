#pragma once
// The landscape of `ftctune landscape` (ftc/tune/run/landscape.hpp) drawn as a heatmap with a log
// colour scale and the optimiser's best-so-far path on top: it shows whether the objective can
// tell gains apart at all.
#include <filesystem>

#include "ftc/tune/job/job.hpp"
#include "ftc/tune/report/report.hpp"
#include "ftc/tune/run/landscape.hpp"

namespace ftc::tune {

struct LandscapeFigureOptions {
  std::filesystem::path history;  // a history.csv whose best-so-far path is drawn on top
  // The run's noise floor (relative spread of the tuned objective, gains.json's noise_floor):
  // grid values within it of the lowest share one colour. 0: unknown.
  double noise_floor = 0.0;
  FigureFormat format = FigureFormat::png;
};

struct LandscapeFigure {
  std::filesystem::path figure;
  // History rows drawn, and those of them that lie on the map (their unplotted parameters at
  // the fixed values); the others are drawn projected.
  int path_points = 0, path_on_map = 0;
};

// Draws `out_dir`/landscape.png (or .svg) from `out_dir`/landscape.csv (landscape_csv(l), which
// the caller wrote): the relative excess over the lowest point, objective/lowest - 1, on a log
// colour scale, each axis with its unit (a log-scale parameter against log10 of its value), the
// best grid point and, with a history, the optimiser's best-so-far path (copied beside it with
// its points in path.csv).
LandscapeFigure draw_landscape(const Job& job, const Landscape& l,
                               const std::filesystem::path& out_dir,
                               const LandscapeFigureOptions& options);

}  // namespace ftc::tune
