#include "report/figures.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <limits>
#include <set>
#include <sstream>

#include "ftc/sim/plants.hpp"
#include "ftc/tune/io/files.hpp"
#include "ftc/tune/run/documents.hpp"
#include "io/decimal.hpp"
#include "io/text.hpp"

namespace ftc::tune::report_detail {

namespace fs = std::filesystem;
using nlohmann::json;
using plot::gp;
using plot::num;
using plot::Series;

namespace {

std::string capitalised(std::string s) {
  if (!s.empty()) s[0] = static_cast<char>(std::toupper(static_cast<unsigned char>(s[0])));
  return s;
}

// A trajectory CSV, column by column.
using Columns = std::vector<std::vector<double>>;

Columns read_columns(const fs::path& file) {
  const std::optional<std::string> text = read_file(file);
  if (!text) throw InputError(file.string(), "", "cannot be read");
  const char* p = text->data();
  const char* const end = p + text->size();
  const char* nl = std::find(p, end, '\n');
  Columns c(static_cast<std::size_t>(std::count(p, nl, ',')) + 1);
  p = nl == end ? end : nl + 1;
  while (p < end) {
    for (std::size_t i = 0; i < c.size(); ++i) {
      double v = 0;
      const std::from_chars_result r = std::from_chars(p, end, v);
      const char expected = i + 1 < c.size() ? ',' : '\n';
      if (r.ec != std::errc() || r.ptr == end || *r.ptr != expected)
        throw InputError(file.string(), "", "is not a trajectory CSV (damaged output?)");
      c[i].push_back(v);
      p = r.ptr + 1;
    }
  }
  return c;
}

// Where a panel draws: data ranges and the plot area's size in pixels (roughly: enough to decide
// what a reader can tell apart). A log axis is described by log10 of its ends.
struct Frame {
  double x0 = 0, x1 = 1, y0 = 0, y1 = 1;
  double width_px = 600, height_px = 200;
  bool log_y = false;
};

// Width of the columns a curve is reduced to its extremes in: two pixels of a dense band look the
// same whichever samples drew them.
constexpr double kColumnPx = 2;

// The points of y(t) a reader can tell apart at the frame's resolution. First, per column,
// the first, last, lowest and highest points (a chattering signal keeps its envelope); then
// Ramer-Douglas-Peucker drops every point whose removal moves the line by under half a pixel (a
// smooth curve keeps a few dozen). Points that cannot be drawn (non-finite, or not positive on a
// log axis) are left out.
std::vector<std::pair<double, double>> visible_points(const std::vector<double>& t,
                                                      const std::vector<double>& y,
                                                      const Frame& f) {
  struct P {
    double px, py, t, y;
  };
  const double sx = f.width_px / (f.x1 - f.x0), sy = f.height_px / (f.y1 - f.y0);
  std::vector<P> pts;
  int column = std::numeric_limits<int>::min();
  std::size_t first = 0, lo = 0, hi = 0, last = 0;
  std::vector<P> all;
  all.reserve(t.size());
  for (std::size_t k = 0; k < t.size() && k < y.size(); ++k) {
    if (!std::isfinite(y[k]) || (f.log_y && !(y[k] > 0))) continue;
    const double yy = f.log_y ? std::log10(y[k]) : y[k];
    all.push_back({(t[k] - f.x0) * sx, (yy - f.y0) * sy, t[k], y[k]});
  }
  const auto flush = [&] {
    if (column == std::numeric_limits<int>::min()) return;
    std::size_t picks[4] = {first, lo, hi, last};
    std::sort(picks, picks + 4);
    for (int i = 0; i < 4; ++i)
      if (i == 0 || picks[i] != picks[i - 1]) pts.push_back(all[picks[i]]);
  };
  for (std::size_t k = 0; k < all.size(); ++k) {
    const int c = static_cast<int>(std::floor(all[k].px / kColumnPx));
    if (c != column) {
      flush();
      column = c;
      first = lo = hi = k;
    }
    if (all[k].py < all[lo].py) lo = k;
    if (all[k].py > all[hi].py) hi = k;
    last = k;
  }
  flush();

  std::vector<char> keep(pts.size(), 0);
  if (!pts.empty()) keep.front() = keep.back() = 1;
  std::vector<std::pair<std::size_t, std::size_t>> todo;
  if (pts.size() > 2) todo.push_back({0, pts.size() - 1});
  while (!todo.empty()) {
    const auto [a, b] = todo.back();
    todo.pop_back();
    const double dx = pts[b].px - pts[a].px, dy = pts[b].py - pts[a].py;
    const double len = std::hypot(dx, dy);
    double worst = -1;
    std::size_t at = a;
    for (std::size_t k = a + 1; k < b; ++k) {
      const double ex = pts[k].px - pts[a].px, ey = pts[k].py - pts[a].py;
      const double d = len > 0 ? std::fabs(dx * ey - dy * ex) / len : std::hypot(ex, ey);
      if (d > worst) {
        worst = d;
        at = k;
      }
    }
    if (worst > 0.5) {
      keep[at] = 1;
      if (at - a > 1) todo.push_back({a, at});
      if (b - at > 1) todo.push_back({at, b});
    }
  }
  std::vector<std::pair<double, double>> out;
  for (std::size_t k = 0; k < pts.size(); ++k)
    if (keep[k]) out.push_back({pts[k].t, pts[k].y});
  return out;
}

// The range a set of curves spans on a linear axis, with 4 % of air; or on a log axis, as
// log10 of its ends, at most twelve decades down from the top.
std::pair<double, double> span_of(const std::vector<const std::vector<double>*>& curves,
                                  bool log_y) {
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (const std::vector<double>* c : curves)
    for (double v : *c) {
      if (!std::isfinite(v) || (log_y && !(v > 0))) continue;
      const double x = log_y ? std::log10(v) : v;
      lo = std::min(lo, x);
      hi = std::max(hi, x);
    }
  if (!(lo <= hi)) return {0, 1};
  if (log_y) lo = std::max(lo, hi - 12);
  const double pad = hi > lo ? 0.04 * (hi - lo) : std::max(0.5, 0.1 * std::fabs(hi));
  return {lo - pad, hi + pad};
}

// A script under construction: the curves as inline data blocks (so figures/report.gp redraws
// the figures on its own) and the plot commands.
class Script {
 public:
  std::ostringstream text;

  // A curve's visible points as a data block; returns its name.
  std::string curve(const std::vector<double>& t, const std::vector<double>& y, const Frame& f) {
    const std::string name = "$c" + std::to_string(++blocks_);
    text << name << " << EOD\n";
    for (const auto& [x, v] : visible_points(t, y, f)) text << num(x) << ',' << num(v) << '\n';
    text << "EOD\n";
    return name;
  }

  // Plot clauses for a curve drawn in line style `ls` with its markers (named in this order).
  std::string line_with_markers(const std::vector<double>& t, const std::vector<double>& y,
                                const Frame& f, int ls, int rank, int ranks) {
    const std::string line = curve(t, y, f);
    const std::string marks = markers(t, y, f, rank, ranks);
    const std::string style = " ls " + std::to_string(ls) + " notitle, ";
    return line + " using 1:2 with lines" + style + marks + " using 1:2 with points" + style;
  }

  // Markers every so often along a curve, shifted by the series' rank so that markers of curves
  // lying on one another do not hide each other.
  std::string markers(const std::vector<double>& t, const std::vector<double>& y, const Frame& f,
                      int rank, int ranks) {
    const std::string name = "$m" + std::to_string(++blocks_);
    text << name << " << EOD\n";
    constexpr int kCount = 8;
    for (int m = 0; m < kCount; ++m) {
      const double at = f.x0 + (f.x1 - f.x0) * (m + (rank + 1.0) / (ranks + 1.0)) / kCount;
      const auto it = std::lower_bound(t.begin(), t.end(), at);
      if (it == t.end()) break;
      const std::size_t k = static_cast<std::size_t>(it - t.begin());
      if (k < y.size() && std::isfinite(y[k]) && (!f.log_y || y[k] > 0))
        text << num(t[k]) << ',' << num(y[k]) << '\n';
    }
    text << "EOD\n";
    return name;
  }

 private:
  int blocks_ = 0;
};

std::string range_text(const Frame& f) {
  return "set xrange [" + num(f.x0) + ":" + num(f.x1) + "]\nset yrange [" +
         (f.log_y ? num(std::pow(10.0, f.y0)) + ":" + num(std::pow(10.0, f.y1))
                  : num(f.y0) + ":" + num(f.y1)) +
         "]\n";
}

// Each controller's line style, by its type (plot::controller_style), minus one: the same
// controller type is drawn alike in every report.
std::vector<int> style_ranks(const std::vector<Series>& series) {
  std::vector<int> rank;
  for (int style : plot::controller_style_list(series)) rank.push_back(style - 1);
  return rank;
}

}  // namespace

std::vector<Figure> draw_run_figures(const fs::path& run_dir, const Job& job, const json& gains,
                                     const std::vector<Series>& series, FigureFormat fmt) {
  const sim::PlantKind& kind = *sim::find_plant_kind(job.plant.model);
  const int n = kind.axes, m = kind.actuators_of(job.plant.values);
  // Trajectory columns: time, x1..x2n, ud1..udm, u1..um.
  const int first_position = 1, first_rate = 1 + n, first_command = 1 + 2 * n,
            first_applied = 1 + 2 * n + m;
  const std::string ext = plot::extension(fmt);
  const sim::Scenario& sc0 = job.scenarios.front();
  std::vector<double> onsets;
  for (const sim::Fault& f : sc0.faults)
    if (f.onset < sc0.duration) onsets.push_back(f.onset);
  std::sort(onsets.begin(), onsets.end());
  onsets.erase(std::unique(onsets.begin(), onsets.end()), onsets.end());
  const std::string scen = job.scenarios.size() > 1 ? " (scenario " + sc0.name + ")" : "";
  const bool paper = job.plant.model == "spacecraft";

  const std::size_t S = series.size();
  std::vector<Columns> data;
  for (const Series& s : series) {
    data.push_back(read_columns(run_dir / s.file));
    if (data.back().size() != static_cast<std::size_t>(1 + 2 * n + 2 * m))
      throw InputError((run_dir / s.file).string(), "",
                       "does not have the columns of a " + job.plant.model + " trajectory");
  }
  const std::vector<int> rank = style_ranks(series);
  std::size_t tuned = S;
  for (std::size_t i = 0; i < S; ++i)
    if (series[i].tuned) tuned = i;

  Script sc;
  std::ostringstream& g = sc.text;
  g << plot::styles(0) << plot::controller_styles();
  std::vector<Figure> figures;
  const auto key_entries = [&](const std::vector<std::size_t>& which) {
    std::string s;
    for (std::size_t i : which)
      s += "keyentry with linespoints ls " + std::to_string(rank[i] + 1) + " title " +
           gp(series[i].label) + ", ";
    return s;
  };
  std::vector<std::size_t> everyone(S), others;
  for (std::size_t i = 0; i < S; ++i) {
    everyone[i] = i;
    if (i != tuned) others.push_back(i);
  }
  // The tuned controller is drawn first, underneath (and thinner): its chattering band then
  // hides no other curve.
  std::vector<std::size_t> drawing_order;
  if (tuned < S) drawing_order.push_back(tuned);
  for (std::size_t i : others) drawing_order.push_back(i);

  // Figures 3 and 4: the states in n panels; beside each, how far every other controller is
  // from the tuned one (log scale), which shows what overlapping curves hide.
  const auto states = [&](const std::string& name, int first_col, const std::string& what,
                          const std::string& unit, int symbol_offset, const std::string& title,
                          const std::string& caption) {
    const std::string file = "figures/" + name + ext;
    const bool diff = tuned < S && S > 1;
    const int width = diff ? 1400 : 1100, top = 80, row = 250, height = top + n * row + 30;
    g << plot::terminal(fmt, width, height) << "set output " << gp(file) << "\n"
      << "set multiplot title " << gp(title + scen) << " font ',13'\n"
      << "set key at screen 0.5, screen " << num(1.0 - 34.0 / height)
      << " center top horizontal maxrows 1 opaque noenhanced\n";
    const double left_end = diff ? 0.49 : 0.96;
    for (int i = 0; i < n; ++i) {
      const int col = first_col + i;
      const std::string axis = i < static_cast<int>(kind.axis_names.size())
                                   ? kind.axis_names[static_cast<std::size_t>(i)] + " "
                                   : "";
      const std::string symbol = "x_" + std::to_string(symbol_offset + i + 1);
      const double y_top = 1.0 - static_cast<double>(top + i * row) / height,
                   y_bottom = y_top - (row - 45.0) / height;
      g << "set tmargin at screen " << num(y_top) << "\nset bmargin at screen " << num(y_bottom)
        << "\n"
        << plot::onset_marks(onsets, i == 0)
        << (i == n - 1 ? "set xlabel 'time [s]'\n" : "unset xlabel\n");
      // The states.
      std::vector<const std::vector<double>*> curves;
      for (std::size_t s = 0; s < S; ++s) curves.push_back(&data[s][static_cast<std::size_t>(col)]);
      Frame f;
      f.x0 = 0;
      f.x1 = sc0.duration;
      std::tie(f.y0, f.y1) = span_of(curves, false);
      f.width_px = (left_end - 0.07) * width;
      f.height_px = row - 45.0;
      std::string plot_cmd = "plot " + key_entries(everyone);
      for (std::size_t s : drawing_order) {
        plot_cmd += sc.line_with_markers(data[s][0], *curves[s], f, rank[s] + 1, rank[s],
                                         plot::kControllerStyles);
      }
      g << "set lmargin at screen 0.07\nset rmargin at screen " << num(left_end) << "\n"
        << (i == 0 ? "set key on\n" : "unset key\n") << "unset logscale y\nset format y '%g'\n"
        << range_text(f) << "set ylabel "
        << gp(axis + (what.empty() ? "" : what + " ") + symbol + " [" + unit + "]") << "\n"
        << plot_cmd.substr(0, plot_cmd.size() - 2) << "\n";
      if (!diff) continue;
      // |x - x_tuned| of the others, where the two have samples at the same times.
      std::vector<std::vector<double>> gaps;
      std::vector<const std::vector<double>*> gap_curves;
      for (std::size_t s : others) {
        const std::vector<double>& a = data[s][static_cast<std::size_t>(col)];
        const std::vector<double>& b = data[tuned][static_cast<std::size_t>(col)];
        std::vector<double> d(std::min(a.size(), b.size()), NAN);
        for (std::size_t k = 0; k < d.size(); ++k)
          if (std::fabs(data[s][0][k] - data[tuned][0][k]) <= 1e-9 * (1 + data[s][0][k]))
            d[k] = std::fabs(a[k] - b[k]);
        gaps.push_back(std::move(d));
      }
      for (const auto& d : gaps) gap_curves.push_back(&d);
      Frame fd = f;
      fd.log_y = true;
      std::tie(fd.y0, fd.y1) = span_of(gap_curves, true);
      fd.width_px = 0.40 * width;
      std::string diff_cmd = "plot ";
      for (std::size_t j = 0; j < others.size(); ++j) {
        const std::size_t s = others[j];
        diff_cmd += sc.line_with_markers(data[s][0], gaps[j], fd, rank[s] + 1, rank[s],
                                         plot::kControllerStyles);
      }
      g << "set lmargin at screen 0.57\nset rmargin at screen 0.97\nunset key\n"
        << "set logscale y\nset format y '10^{%L}'\n"
        << range_text(fd) << "set ylabel "
        << gp("|" + symbol + " − " + symbol + "^{tuned}| [" + unit + "]") << "\n"
        << diff_cmd.substr(0, diff_cmd.size() - 2) << "\n";
    }
    g << "unset multiplot\nunset logscale y\nset format y '%g'\nset autoscale\nunset xlabel\n"
         "unset tmargin\nunset bmargin\nunset lmargin\nunset rmargin\nunset arrow\nunset label\n"
         "set key default\nset key outside right top vertical box opaque\n";
    figures.push_back({file, title, caption});
  };
  const std::string diff_caption =
      tuned < S && S > 1 ? " Right: the distance of every other controller from the tuned one, "
                           "log scale; it shows where curves on the left lie on one another."
                         : "";
  states("fig3-attitude", first_position, "", kind.position_unit, 0,
         capitalised(kind.positions) + " under actuator faults" + (paper ? " (paper Fig. 3)" : ""),
         capitalised(kind.positions) +
             " X1 of every compared controller; dashed lines mark the fault onsets." +
             diff_caption);
  states("fig4-rates", first_rate, "rate", kind.rate_unit, n,
         capitalised(kind.rates) + " under actuator faults" + (paper ? " (paper Fig. 4)" : ""),
         capitalised(kind.rates) + " X2 of every compared controller." + diff_caption);

  // Figure 5: convergence, as the relative improvement of the objective (1/J) over the job's
  // own controller: the best J alone reads 0.7496 -> 0.7508, which hides how much changed.
  {
    const std::string file = "figures/fig5-fitness" + ext;
    const std::string type = gains["optimizer"].value("type", "bat");
    const std::string algorithm =
        type == "bat"      ? "Bat algorithm"
        : type == "random" ? "random search"
        : type == "pagmo"  ? "pagmo " + gains["optimizer"].value("name", std::string("?"))
                           : type;
    // A number of the gains file, NaN where it has none.
    const auto number_at = [&](const char* pointer) {
      return json_number_or(gains.value(json::json_pointer(pointer), json()), NAN);
    };
    const double baseline_j = number_at("/baseline/fitness");
    const bool have_baseline = std::isfinite(baseline_j) && baseline_j > 0;
    // The improvement as a ratio on a log axis, reference objective / best objective − 1
    // = J / J_ref − 1, so that 0.1 % and 1 000 times both read: a percent scale squeezes a small
    // gain into its floor and saturates a large one at 100 %.
    const std::string reference = have_baseline ? num(baseline_j) : "J0";
    g << plot::terminal(fmt, 1000, 600) << "set output " << gp(file) << "\n"
      << "unset arrow; unset label\nset title "
      << gp("Improvement per iteration of " + objective_label(job) +
            (paper ? " (paper Fig. 5)" : ""))
      << " font ',13'\n"
      << "set xlabel 'iteration'\nset ylabel "
      << gp(std::string(have_baseline ? "job's controller's" : "initial population's best") +
            " objective / best so far − 1 (log scale)")
      << "\nset logscale y\nset ytics ('+0.00001 %%' 1e-7, '+0.0001 %%' 1e-6, '+0.001 %%' 1e-5, "
         "'+0.01 %%' 1e-4, '+0.1 %%' 1e-3, '+0.2 %%' 2e-3, '+0.5 %%' 5e-3, '+1 %%' 1e-2, "
         "'+2 %%' 2e-2, '+5 %%' 5e-2, '+10 %%' 0.1, '+20 %%' 0.2, '+50 %%' 0.5, '2×' 1, "
         "'3×' 2, '5×' 4, '10×' 9, '30×' 29, '100×' 99, '300×' 299, '1 000×' 999, "
         "'10 000×' 9999)\nset key inside right bottom opaque box\n";
    if (!have_baseline)
      g << "J0 = 0\nstats 'history.csv' skip 1 every ::0::0 using 2 nooutput\nJ0 = STATS_max\n";
    const double floor = number_at("/noise_floor/relative_spread");
    // Iterations not better than the reference have no logarithm: not drawn.
    const std::string ratio = "(($2/" + reference + " - 1) > 0 ? ($2/" + reference + " - 1) : 1/0)";
    g << "plot 'history.csv' skip 1 using 1:" << ratio << " with linespoints ls 1 lw 2 title "
      << gp(algorithm);
    if (fs::is_regular_file(run_dir / "history-random.csv"))
      g << ", \\\n     'history-random.csv' skip 1 using 1:" << ratio
        << " with linespoints ls 4 lw 2 title 'random search, same budget'";
    // The noise floor as a line that autoscaling keeps in view.
    if (std::isfinite(floor) && floor > 0)
      g << ", \\\n     " << num(floor) << " with lines dt 3 lw 1.5 lc rgb 'gray40' title "
        << gp("noise floor " + detail::format_number(100 * floor, "%.2g") + " %");
    g << "\nunset logscale y\nset autoscale y\nset ytics autofreq\nset format y '%g'\nunset "
         "title\nunset "
         "arrow\nunset label\n"
         "set key default\nset key outside right top vertical box opaque\n";
    figures.push_back(
        {file, "Convergence",
         std::string("How much lower the best objective found so far is than ") +
             (have_baseline ? "the job's own controller's" : "the initial population's best") +
             ", after each iteration (iteration 0 is the initial population), as the ratio "
             "minus one on a log axis: +0.1 % and 1 000× both read. An iteration not better "
             "than that reference is not drawn. Changes under the noise floor (dotted, when "
             "measured) are not real."});
  }

  // Figure 6: commanded and applied outputs per controller, every panel on one y scale so that
  // controllers compare at a glance, with the actuators' limits: without them saturation could
  // not be seen (issue 41). Applied outputs are drawn for the faulted actuators, and for every
  // actuator when the commands have a limit (the scenario's or the plant's).
  {
    const std::string file = "figures/fig6-inputs" + ext;
    const std::size_t rows = (S + 1) / 2;
    const std::vector<std::pair<double, double>> limits =
        sim::make_plant(job.plant)->command_limits(sc0);
    std::set<double> limit_values;  // each finite limit once
    for (const auto& [lo, hi] : limits)
      for (const double v : {lo, hi})
        if (std::isfinite(v)) limit_values.insert(v);
    std::set<int> faulted;
    for (const sim::Fault& f : sc0.faults) faulted.insert(f.actuator);
    if (!limit_values.empty())
      for (int j = 1; j <= m; ++j) faulted.insert(j);
    std::vector<const std::vector<double>*> curves;
    for (std::size_t s = 0; s < S; ++s) {
      for (int j = 0; j < m; ++j)
        curves.push_back(&data[s][static_cast<std::size_t>(first_command + j)]);
      for (int j : faulted)
        curves.push_back(&data[s][static_cast<std::size_t>(first_applied + j - 1)]);
    }
    Frame f;
    f.x1 = sc0.duration;
    std::tie(f.y0, f.y1) = span_of(curves, false);
    f.width_px = 460;
    f.height_px = 280;
    g << plot::line_styles(m) << plot::terminal(fmt, 1200, static_cast<int>(430 * rows + 60))
      << "set output " << gp(file) << "\nset multiplot layout " << rows << ",2 title "
      << gp(std::string("Actuator outputs") + (paper ? " (paper Fig. 6)" : "") + scen)
      << " font ',13'\n"
      << plot::onset_marks(onsets, true) << range_text(f) << "set xlabel 'time [s]'\n"
      << "set ylabel " << gp("actuator output u [" + kind.command_unit + "]")
      << "\nset key below horizontal font ',9' maxrows 2 enhanced\nset bmargin 7\n";
    // The limits, as grey dash-dot lines across every panel (those outside the data's range
    // are not reached, and not drawn).
    int arrow = 1000;
    for (const double v : limit_values)
      if (v >= f.y0 && v <= f.y1)
        g << "set arrow " << arrow++ << " from graph 0, first " << num(v)
          << " to graph 1, first " << num(v)
          << " nohead lc rgb '#777777' lw 1.5 dt (8,4,2,4) back\n";
    for (std::size_t s = 0; s < S; ++s) {
      std::string cmd = "plot ";
      for (int j = 1; j <= m; ++j) {
        const std::vector<double>& u = data[s][static_cast<std::size_t>(first_command + j - 1)];
        cmd += "keyentry with linespoints ls " + std::to_string(j) + " title 'u_{d" +
               std::to_string(j) + "}', ";
        cmd += sc.line_with_markers(data[s][0], u, f, j, j - 1, m);
      }
      for (int j : faulted) {
        const std::vector<double>& u = data[s][static_cast<std::size_t>(first_applied + j - 1)];
        cmd += sc.curve(data[s][0], u, f) + " using 1:2 with lines ls " + std::to_string(j) +
               " lw 3 dt (2,3) title 'applied u_" + std::to_string(j) + "', ";
      }
      // One legend for the figure: the first panel's (every panel uses the same styles).
      g << "set title " << gp(series[s].label) << " noenhanced\n"
        << (s == 0 ? "" : "unset key\n") << cmd.substr(0, cmd.size() - 2) << "\n";
    }
    for (int a = 1000; a < arrow; ++a) g << "unset arrow " << a << "\n";
    g << "unset multiplot\nunset title\nset autoscale\nunset bmargin\n"
      << plot::controller_styles()
      << "set key default\nset key outside right top vertical box opaque\n";
    figures.push_back(
        {file, "Actuator outputs",
         "Commanded outputs u_d of each controller (each actuator its own colour, dash and "
         "marker) and, thick dotted in the same colour, the applied output of each faulted "
         "actuator (bias added, effectiveness lost), and of every actuator when the commands "
         "have a limit, in " + kind.command_unit + ". The grey dash-dot lines are the "
         "actuators' limits (a command held at one is saturated). All panels share one scale "
         "and the legend of the first; the faults are the labelled grey dashed lines."});
  }

  // Figure 7: the faulted part, where the controllers differ, on a log scale.
  if (!onsets.empty()) {
    const std::string file = "figures/fig7-fault-zoom" + ext;
    Frame f;
    f.x0 = std::max(0.0, onsets.front() - 1.0);
    f.x1 = sc0.duration;
    f.log_y = true;
    f.width_px = 800;
    f.height_px = 480;
    std::vector<std::vector<double>> norms(S);
    std::vector<const std::vector<double>*> curves;
    for (std::size_t s = 0; s < S; ++s) {
      const std::vector<double>& t = data[s][0];
      for (std::size_t k = 0; k < t.size(); ++k) {
        double sum = 0;
        for (int i = 0; i < n; ++i) {
          const double x = data[s][static_cast<std::size_t>(first_position + i)][k];
          sum += x * x;
        }
        norms[s].push_back(t[k] >= f.x0 ? std::sqrt(sum) : NAN);
      }
      curves.push_back(&norms[s]);
    }
    std::tie(f.y0, f.y1) = span_of(curves, true);
    std::string cmd = "plot " + key_entries(everyone);
    for (std::size_t s : drawing_order) {
      cmd += sc.line_with_markers(data[s][0], norms[s], f, rank[s] + 1, rank[s],
                                  plot::kControllerStyles);
    }
    g << plot::terminal(fmt, 1100, 600) << "set output " << gp(file) << "\n"
      << plot::onset_marks(onsets) << "set title " << gp("Error ‖X_1‖ after the faults" + scen)
      << " font ',13'\nset logscale y\nset format y '10^{%L}'\n"
      << range_text(f) << "set xlabel 'time [s]'\nset ylabel "
      << gp("‖X_1‖ [" + kind.position_unit + "]") << "\nset key noenhanced\n"
      << cmd.substr(0, cmd.size() - 2)
      << "\nunset logscale y\nset format y '%g'\nset autoscale\nunset title\n";
    figures.push_back({file, "Zoom on the faulted part",
                       "Norm of the error X1 from one second before the first fault on, log "
                       "scale: the part of the run the paper's fault-tolerance claims are about."});
  }

  write_file_atomic(run_dir / "figures" / "report.gp", g.str());
  run_gnuplot(run_dir, "figures/report.gp");
  return figures;
}

}  // namespace ftc::tune::report_detail
