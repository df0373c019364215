// The landscape figure (report/landscape.hpp).
#include "ftc/tune/report/landscape.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <sstream>

#include "ftc/sim/controller_config.hpp"
#include "ftc/tune/io/files.hpp"
#include "ftc/tune/run/documents.hpp"
#include "io/text.hpp"
#include "report/gnuplot.hpp"

namespace ftc::tune {

namespace fs = std::filesystem;

namespace {

// A gnuplot string in double quotes, where "\n" breaks the line (single quotes cannot).
std::string double_quoted(const std::string& text) {
  std::string s = "\"";
  for (char c : text) {
    if (c == '\n')
      s += "\\n";
    else if (c == '"' || c == '\\')
      s += std::string("\\") + c;
    else
      s += c;
  }
  return s + "\"";
}

// The unit of a tunable controller field: the controller table's (controller_config.hpp).
std::string parameter_unit(const std::string& name, sim::ControllerType type) {
  const sim::ControllerField* f = sim::find_controller_field(name);
  return f ? f->unit_for(type) : "";
}

}  // namespace

LandscapeFigure draw_landscape(const Job& job, const Landscape& l, const fs::path& out_dir,
                               const LandscapeFigureOptions& options) {
  LandscapeFigure r;
  r.figure = out_dir / (std::string("landscape") + plot::extension(options.format));
  const std::vector<std::string>& params = l.params;
  const std::vector<ParameterBounds>& bounds = l.bounds;
  // A log-scale parameter is drawn against log10 of its value, where the grid is even (gnuplot
  // draws an image on a log axis as if the axis were linear).
  const auto coord = [&](int k, const std::string& column) {
    return bounds[k].scale == Scale::log ? "(log10($" + column + "))" : column;
  };
  const auto axis_end = [&](int k, double v) {
    return bounds[k].scale == Scale::log ? std::log10(v) : v;
  };
  // Half a grid cell beyond the bounds: the cells at the edges, the best point and the optimiser's
  // path are drawn whole.
  const auto range = [&](int k, int n) {
    const double lo = axis_end(k, bounds[k].lower), hi = axis_end(k, bounds[k].upper);
    const double pad = (hi - lo) / (2.0 * (n - 1));
    return detail::format_number(lo - pad, "%.9g") + ":" + detail::format_number(hi + pad, "%.9g");
  };
  // Each axis names its unit (a log-scale parameter: the unit of the value under the log).
  const auto label = [&](int k) {
    const std::string unit = parameter_unit(params[k], job.controller.type);
    const std::string with_unit = unit.empty()              ? params[k]
                                  : unit == "dimensionless" ? params[k] + " (dimensionless)"
                                                            : params[k] + " [" + unit + "]";
    return bounds[k].scale == Scale::log ? "log10 of " + with_unit : with_unit;
  };
  // Coloured by the relative excess over the best point, objective/min − 1, on a log scale: a
  // landscape whose objective spans 0.2 % is then as readable as one that spans decades. The
  // best point itself (excess 0) takes the colour of a tenth of the smallest positive excess.
  const std::string metric = std::string(job.objective.metric->name);
  const double least_excess = l.least_excess;
  // Values within the run's noise floor of the lowest are not told apart: they share the
  // colour of the floor. Without a noise floor, the lowest point takes the colour of a tenth of
  // the smallest positive excess.
  const bool have_noise = options.noise_floor > 0 && std::isfinite(options.noise_floor);
  const double floor_excess = have_noise                    ? options.noise_floor
                              : std::isfinite(least_excess) ? least_excess / 10
                                                            : 1e-12;
  const double most_excess = std::max(l.worst_objective / l.best_objective - 1, 10 * floor_excess);
  const std::string best_text = detail::format_number(l.best_objective, "%.17g");
  const std::string excess = "(($3/" + best_text + " - 1) > " +
                             detail::format_number(floor_excess, "%.17g") + " ? ($3/" + best_text +
                             " - 1) : " + detail::format_number(floor_excess, "%.17g") + ")";
  std::string fixed_text;
  for (const auto& [name, value] : l.fixed)
    fixed_text +=
        (fixed_text.empty() ? "" : ", ") + name + " = " + detail::format_number(value, "%.5g");
  const std::string title =
      objective_label(job) + " of " + job.name + " over " + params[0] + " and " + params[1] +
      "\nlowest on the grid " + detail::format_number(l.best_objective, "%.7g") + " " +
      std::string(job.objective.metric->unit) + " at " + params[0] + " = " +
      detail::format_number(l.best[0], "%.5g") + ", " + params[1] + " = " +
      detail::format_number(l.best[1], "%.5g") +
      (fixed_text.empty() ? std::string()
                          : "\n" + fixed_text + " held fixed (" + l.fixed_source + ")");
  std::ostringstream g;
  g << plot::styles() << plot::terminal(options.format, 1000, 800) << "set output "
    << plot::gp(r.figure.filename().string()) << "\nset title " << double_quoted(title)
    << " font ',13' noenhanced\nset logscale cb\n"
    << plot::colour_tics(
           floor_excess, most_excess,
           have_noise ? "≤ noise floor " + detail::format_number(options.noise_floor, "%.2g") : "")
    << "set cblabel "
    << plot::gp(metric + " / lowest " + metric + " − 1, dimensionless (log scale; lower is better" +
                (have_noise ? "; within the noise floor: one colour)" : ")"))
    << " noenhanced offset -3,0\n"
    << plot::palette() << "set xlabel " << plot::gp(label(0)) << " noenhanced\nset ylabel "
    << plot::gp(label(1)) << " noenhanced\nset xrange [" << range(0, l.n1)
    << "]\nset yrange [" << range(1, l.n2)
    << "]\nset rmargin 24\nset key outside top center horizontal\n"
    << "plot 'landscape.csv' skip 1 using " << coord(0, "1") << ":" << coord(1, "2") << ":"
    << excess << " with image notitle";
  if (!options.history.empty()) {
    if (!fs::is_regular_file(options.history))
      throw InputError(options.history.string(), "", "cannot read the history file");
    std::istringstream hist(read_file(options.history).value_or(""));
    std::string header;
    std::getline(hist, header);
    std::vector<std::string> cols;
    std::stringstream hs(header);
    for (std::string c; std::getline(hs, c, ',');) cols.push_back(c);
    const auto col = [&](const std::string& n) {
      return static_cast<int>(std::find(cols.begin(), cols.end(), n) - cols.begin()) + 1;
    };
    const int c0 = col(params[0]), c1 = col(params[1]);
    if (c0 > static_cast<int>(cols.size()) || c1 > static_cast<int>(cols.size()))
      throw InputError(options.history.string(), "",
                       "has no columns " + params[0] + " and " + params[1]);
    const fs::path copy = out_dir / "history.csv";
    if (fs::absolute(options.history) != fs::absolute(copy))
      fs::copy_file(options.history, copy, fs::copy_options::overwrite_existing);
    // The path's rows, each marked on the map (its unplotted parameters at the fixed values)
    // or not: a row elsewhere is drawn projected, and labelled so.
    std::string path = params[0] + "," + params[1] + ",on_map\n";
    for (std::string row; std::getline(hist, row);) {
      if (row.empty()) continue;
      std::vector<std::string> cells;
      std::stringstream rs(row);
      for (std::string c; std::getline(rs, c, ',');) cells.push_back(c);
      const auto cell = [&](int k) {
        return k - 1 < static_cast<int>(cells.size()) && !cells[k - 1].empty()
                   ? std::stod(cells[k - 1])
                   : NAN;
      };
      bool on = true;
      for (const auto& [name, value] : l.fixed) {
        const int k = col(name);
        const double v = k <= static_cast<int>(cols.size()) ? cell(k) : NAN;
        on = on && std::abs(v - value) <= 1e-9 * std::max(1.0, std::abs(value));
      }
      char buf[160];
      std::snprintf(buf, sizeof buf, "%.17g,%.17g,%d\n", cell(c0), cell(c1), on ? 1 : 0);
      path += buf;
      ++r.path_points;
      r.path_on_map += on ? 1 : 0;
    }
    write_file_atomic(out_dir / "path.csv", path);
    if (r.path_on_map == r.path_points) {
      g << ", \\\n     'path.csv' skip 1 using " << coord(0, "1") << ":" << coord(1, "2")
        << " with linespoints lw 2.5 pt 7 ps 1.3 lc rgb 'black' title 'optimiser: best so far, "
           "by iteration'";
    } else {
      g << ", \\\n     'path.csv' skip 1 using " << coord(0, "1") << ":" << coord(1, "2")
        << " with linespoints lw 2 dt 2 pt 6 ps 1.3 lc rgb 'black' title "
        << plot::gp("optimiser's best so far, projected (other parameters differ)")
        << ", \\\n     'path.csv' skip 1 using " << coord(0, "1") << ":(($3 > 0) ? "
        << (bounds[1].scale == Scale::log ? "log10($2)" : "$2")
        << " : 1/0) with points pt 7 ps 1.5 lc rgb 'black' title 'best so far on the map'";
    }
  }
  g << ", \\\n     '-' using 1:2 with points pt 6 ps 3 lw 3 lc rgb 'black' title 'best grid "
       "point'\n"
    << axis_end(0, l.best[0]) << "," << axis_end(1, l.best[1]) << "\ne\n";
  write_file_atomic(out_dir / "landscape.gp", g.str());
  run_gnuplot(out_dir, "landscape.gp");
  return r;
}

}  // namespace ftc::tune
