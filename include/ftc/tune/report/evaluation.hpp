#pragma once
// The figure of `ftctune evaluate`: how the member objectives are distributed, per controller.
#include <filesystem>

#include "ftc/tune/report/report.hpp"
#include "ftc/tune/run/evaluate.hpp"

namespace ftc::tune {

// Draws `dir`/evaluation.png (or .svg) from `dir`/evaluation.gp: on the left the empirical CDF of
// the objective over the members each controller is scored on (log axis: members differ by
// orders of magnitude), on the right a box plot of the same values. Diverged members have no
// finite value; the key says how many each controller had. Returns the figure's path.
std::filesystem::path draw_evaluation(const EvaluationResult& r, const std::filesystem::path& dir,
                                      FigureFormat format = FigureFormat::png);

}  // namespace ftc::tune
