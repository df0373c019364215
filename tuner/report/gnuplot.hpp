#pragma once
// Pieces of gnuplot scripts shared by the report's figures, the landscape and the study plot.
// Private to tuner/.
#include <string>
#include <vector>

#include "ftc/tune/report/report.hpp"
#include "io/decimal.hpp"

namespace ftc::tune::plot {

// A number as every number of the gnuplot scripts is written: %.9g.
constexpr auto num = &detail::g9_string;

// A string literal for gnuplot (single quotes; a quote inside is doubled).
std::string gp(const std::string& s);
std::string terminal(FigureFormat f, int width, int height);
const char* extension(FigureFormat f);
// Colour-bar tics for a log scale over [lo, hi], at round values (1, 2, 5 × 10^k, or decades
// when those would crowd); with `lo_label`, a first tic at lo that says what lo is.
std::string colour_tics(double lo, double hi, const std::string& lo_label = "");

// viridis at t in [0, 1] as '#rrggbb': perceptually uniform, readable in grey and with the
// common colour-vision deficiencies. Every figure takes its colours from it.
std::string viridis(double t);
// `set palette` for colour maps (landscapes).
std::string palette();
// Line styles 1..count: viridis colours from dark to light, each with its own dash type and
// marker, so curves stay apart in print, in grey and for colour-blind readers.
std::string line_styles(int count);
// What every script starts with: CSV data, line styles 1..count, grid and key.
std::string styles(int count = 6);

struct Series {
  std::string label;
  std::string file;    // relative to the directory the script runs in
  bool tuned = false;  // the controller the run tuned: the others are compared with it
  std::string type;    // the controller type ("pi_fosmc", ...): it picks the line style
};

// One line style per controller type, the same in every report and figure (a reader learns it
// once): the tuned controller 1 (darkest, solid, filled circles), then PI-FOSMC 2, FOSMC 3,
// NFTSMC 4, adaptive neural PI-FOSMC 5; a second controller of one type takes 6.. (same colour,
// its own dash and marker). controller_styles() defines them all.
inline constexpr int kControllerStyles = 10;
int controller_style(const std::string& type, bool tuned, int repeat = 0);
std::string controller_styles();
// Styles for the series in order, repeats of a type told apart.
std::vector<int> controller_style_list(const std::vector<Series>& series);

// Vertical dashed lines at the fault onsets, optionally labelled.
std::string onset_marks(const std::vector<double>& onsets, bool labels = true);

}  // namespace ftc::tune::plot
