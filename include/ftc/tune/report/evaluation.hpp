#pragma once
// The figure of `ftctune evaluate`: how the member objectives are distributed, per controller.
#include <filesystem>

#include "ftc/tune/report/report.hpp"
#include "ftc/tune/run/evaluate.hpp"
#include "ftc/tune/run/front.hpp"

namespace ftc::tune {

// Draws `dir`/evaluation.png (or .svg) from `dir`/evaluation.gp: on the left the empirical CDF of
// the objective over the members each controller is scored on (log axis: members differ by
// orders of magnitude), on the right a box plot of the same values. Diverged members have no
// finite value; the key says how many each controller had. Returns the figure's path.
std::filesystem::path draw_evaluation(const EvaluationResult& r, const std::filesystem::path& dir,
                                      FigureFormat format = FigureFormat::png);

// Draws `dir`/front-held-out.png (or .svg) from `dir`/front-held-out.gp for a held-out front
// (`evaluate --front`, Front::held_out): on the first two soft goals, each point of the run's
// front where the run put it (in sample, open) and where the held-out members put it (filled
// when it stays on the held-out front, a cross when it drops off), a line joining the two, the
// held-out knee ringed and the compared controllers' held-out values marked. Returns the
// figure's path; none for a front without a point or with fewer than two soft goals.
std::filesystem::path draw_held_out_front(const Front& front, const std::filesystem::path& dir,
                                          FigureFormat format = FigureFormat::png);

}  // namespace ftc::tune
