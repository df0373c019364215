#include "ftc/tune/report/study_figure.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

#include "ftc/tune/io/files.hpp"
#include "io/text.hpp"
#include "report/gnuplot.hpp"

namespace ftc::tune {

namespace fs = std::filesystem;

fs::path draw_study(const fs::path& dir, const std::string& title,
                    const std::string& objective_label, const std::vector<StudySeries>& series,
                    FigureFormat format, double best_median, double noise_floor) {
  double lo = std::numeric_limits<double>::infinity(), hi = 0.0;
  for (const StudySeries& s : series)
    for (double v : s.objectives)
      if (std::isfinite(v) && v > 0) {
        lo = std::min(lo, v);
        hi = std::max(hi, v);
      }
  const bool log_scale = hi >= 10 * lo;
  const fs::path figure = dir / (std::string("study") + plot::extension(format));
  std::ostringstream g;
  g << plot::styles() << plot::terminal(format, 1000, 600) << "set output "
    << plot::gp(figure.filename().string()) << "\nset title " << plot::gp(title)
    << " font ',13'\nset ylabel " << plot::gp(objective_label) << "\n"
    << (log_scale ? "set logscale y\nset format y '%.3g'\n" : "set format y '%.6g'\n")
    << "set xrange [-0.6:" << series.size() - 0.4 << "]\nset xtics noenhanced rotate by -30 left (";
  for (std::size_t i = 0; i < series.size(); ++i)
    g << (i ? ", " : "") << plot::gp(series[i].label) << " " << i;
  // Algorithm names keep their underscores (no enhanced-text subscripts). The key goes top left:
  // callers order the algorithms best median first, so that corner is the emptiest.
  g << ")\nset grid xtics ytics lc rgb '#dddddd'\nset key inside top left opaque box\n"
    << "$runs << EOD\n";
  // Runs side by side within an algorithm's slot, in seed order, so equal results stay visible.
  for (std::size_t i = 0; i < series.size(); ++i) {
    const std::size_t n = series[i].objectives.size();
    for (std::size_t k = 0; k < n; ++k) {
      const double v = series[i].objectives[k];
      if (!std::isfinite(v) || (log_scale && v <= 0)) continue;
      const double dx =
          n > 1 ? 0.5 * (static_cast<double>(k) / static_cast<double>(n - 1) - 0.5) : 0.0;
      g << detail::format_number(static_cast<double>(i) + dx, "%.6g") << ","
        << detail::format_number(v, "%.17g") << "\n";
    }
  }
  g << "EOD\n$medians << EOD\n";
  for (std::size_t i = 0; i < series.size(); ++i) {
    std::vector<double> v = series[i].objectives;
    if (v.empty()) continue;
    std::sort(v.begin(), v.end());
    const double m = v.size() % 2 ? v[v.size() / 2] : 0.5 * (v[v.size() / 2 - 1] + v[v.size() / 2]);
    if (!std::isfinite(m)) continue;
    g << static_cast<double>(i) - 0.35 << "," << detail::format_number(m, "%.17g") << ",0.7,0\n";
  }
  // The noise band: from the best median to noise_floor above it.
  const bool band = best_median > 0 && noise_floor > 0 && std::isfinite(noise_floor);
  g << "EOD\n";
  if (band)
    g << "set object 1 rect from graph 0, first " << detail::format_number(best_median, "%.17g")
      << " to graph 1, first " << detail::format_number(best_median * (1 + noise_floor), "%.17g")
      << " behind fillcolor rgb 'gray70' fillstyle solid 0.5 noborder\n";
  g << "plot $runs using 1:2 with points pt 7 ps 1.1 lc rgb '" << plot::viridis(0.45)
    << "' title 'best "
       "objective of one run (one point per seed)', \\\n"
    << "     $medians using 1:2:3:4 with vectors nohead lw 3 lc rgb '" << plot::viridis(0)
    << "' title 'median'";
  if (band)
    g << ", \\\n     NaN with boxes fillcolor rgb 'gray70' fillstyle solid 0.5 title "
      << plot::gp("within the noise floor (" + detail::format_number(100 * noise_floor, "%.2g") +
                  " %) of the best median: not told apart");
  g << "\n";
  write_file_atomic(dir / "study.gp", g.str());
  run_gnuplot(dir, "study.gp");
  return figure;
}

}  // namespace ftc::tune
