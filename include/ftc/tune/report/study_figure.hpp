#pragma once
// The figure of `ftctune study`: the best objective of each run, per algorithm.
#include <filesystem>
#include <string>
#include <vector>

#include "ftc/tune/report/report.hpp"

namespace ftc::tune {

// One algorithm's results in a comparison: the best objective of each run (one per seed).
struct StudySeries {
  std::string label;
  std::vector<double> objectives;  // +inf for a run whose every candidate diverged
};

// Draws `dir`/study.png (or .svg) from `dir`/study.gp: one point per run for each algorithm, in
// the order given (best median first keeps the key clear of the points), with each algorithm's
// median marked; the objective axis is logarithmic when the finite objectives span a factor of
// 10 or more. With a noise floor (relative) and the best median, a grey band marks the values
// within the noise of the best median: medians inside it are not told apart. Returns the
// figure's path.
std::filesystem::path draw_study(const std::filesystem::path& dir, const std::string& title,
                                 const std::string& objective_label,
                                 const std::vector<StudySeries>& series,
                                 FigureFormat format = FigureFormat::png, double best_median = 0.0,
                                 double noise_floor = 0.0);

}  // namespace ftc::tune
