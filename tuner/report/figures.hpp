#pragma once
// The figures of a tuning run (paper Figs. 3-6 and a zoom on the faults), drawn with gnuplot from
// the trajectories the run wrote, for a plant of any shape. Private to tuner/report.
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "ftc/tune/job/job.hpp"
#include "report/gnuplot.hpp"

namespace ftc::tune::report_detail {

struct Figure {
  std::string file;  // relative to the run directory
  std::string title, caption;
};

// Writes figures/report.gp and runs it. `series` holds, per compared controller, its label and
// the trajectory CSV of the job's first scenario.
std::vector<Figure> draw_run_figures(const std::filesystem::path& run_dir, const Job& job,
                                     const nlohmann::json& gains,
                                     const std::vector<plot::Series>& series, FigureFormat format);

}  // namespace ftc::tune::report_detail
