#pragma once
// The Pareto front of a run with two or more soft goals (RUN/front.json, written by `ftctune
// run` and read back by front_from_json, ftc/tune/run/front.hpp): drawn as a pairwise scatter of
// the soft goals and as the hypervolume per iteration. Private to tuner/report.
#include <filesystem>
#include <vector>

#include "ftc/tune/report/report.hpp"
#include "ftc/tune/run/front.hpp"
#include "report/figures.hpp"

namespace ftc::tune::report_detail {

// Writes figures/front.gp (the pairwise scatter and the hypervolume over the iterations of
// RUN/history.csv) and runs it.
std::vector<Figure> draw_front_figures(const std::filesystem::path& run_dir, const Front& front,
                                       FigureFormat format);

}  // namespace ftc::tune::report_detail
