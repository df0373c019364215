#pragma once
// Pieces of gnuplot scripts shared by the report's figures, the landscape and the study plot.
// Private to tuner/.
#include <string>
#include <vector>

#include "ftc/tune/report/report.hpp"

namespace ftc::tune::plot {

// A string literal for gnuplot (single quotes; a quote inside is doubled).
std::string gp(const std::string& s);
std::string terminal(FigureFormat f, int width, int height);
const char* extension(FigureFormat f);
// Colour-bar tics for a log scale over [lo, hi].
std::string colour_tics(double lo, double hi);

struct Series {
  std::string label;
  std::string file;  // relative to the directory the script runs in
};

// Vertical dashed lines at the fault onsets, optionally labelled.
std::string onset_marks(const std::vector<double>& onsets, bool labels = true);
// One line per series of the CSV columns `using_expr`.
std::string series_plot(const std::vector<Series>& series, const std::string& using_expr,
                        bool titles);

// Line styles, grid and key every script starts with.
extern const char* const kStyles;

}  // namespace ftc::tune::plot
