#include "report/front_figures.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <limits>
#include <sstream>

#include "ftc/sim/input_error.hpp"
#include "ftc/tune/io/files.hpp"
#include "ftc/tune/report/evaluation.hpp"
#include "io/decimal.hpp"
#include "io/text.hpp"
#include "report/gnuplot.hpp"

namespace ftc::tune::report_detail {

namespace fs = std::filesystem;
using plot::gp;
using plot::num;

namespace {

// A goal's noise floor at a point, relative; NaN where the run measured none.
double floor_at(const FrontPoint& p, std::size_t g) { return p.noise_floor[g].value_or(NAN); }

// A goal's column of the points and the compared controllers, and whether a log axis can show it.
bool log_axis(const Front& front, std::size_t g) {
  for (const FrontPoint& p : front.points)
    if (std::isfinite(p.goals[g]) && !(p.goals[g] > 0)) return false;
  for (const FrontCompared& c : front.compared)
    if (std::isfinite(c.goals[g]) && !(c.goals[g] > 0)) return false;
  return true;
}

// The noise band of value v with relative spread f: v·(1 ± f/2), kept above a tenth of v on a
// log axis.
std::pair<double, double> band(double v, double f, bool log) {
  if (!std::isfinite(f)) return {v, v};
  double lo = v - 0.5 * f * std::fabs(v), hi = v + 0.5 * f * std::fabs(v);
  if (log) lo = std::max(lo, 0.1 * v);
  return {lo, hi};
}

// The iterations and the hypervolume column of history.csv.
std::vector<std::pair<double, double>> hypervolume_history(const fs::path& file) {
  const std::optional<std::string> text = read_file(file);
  if (!text) throw InputError(file.string(), "", "cannot be read");
  std::istringstream in(*text);
  std::string line;
  std::getline(in, line);
  std::vector<std::string> header;
  {
    std::istringstream cells(line);
    std::string cell;
    while (std::getline(cells, cell, ',')) header.push_back(cell);
  }
  const auto at = std::find(header.begin(), header.end(), "hypervolume");
  if (at == header.end())
    throw InputError(file.string(), "",
                     "has no hypervolume column, which a run with a front writes (damaged "
                     "output?)");
  const std::size_t col = static_cast<std::size_t>(at - header.begin());
  std::vector<std::pair<double, double>> rows;
  while (std::getline(in, line)) {
    if (line.empty()) continue;
    std::vector<std::string> cells;
    std::size_t from = 0;
    for (;;) {
      const std::size_t comma = line.find(',', from);
      cells.push_back(line.substr(from, comma == std::string::npos ? comma : comma - from));
      if (comma == std::string::npos) break;
      from = comma + 1;
    }
    if (cells.size() != header.size())
      throw InputError(file.string(), "",
                       "has a row of " + std::to_string(cells.size()) +
                           " cells under a header of " + std::to_string(header.size()));
    const auto parse = [&](const std::string& c) {
      double v = NAN;
      if (c.empty()) return v;
      const std::from_chars_result r = std::from_chars(c.data(), c.data() + c.size(), v);
      if (r.ec != std::errc() || r.ptr != c.data() + c.size())
        throw InputError(file.string(), "", "has a cell that is not a number: " + c);
      return v;
    };
    const double it = parse(cells[0]), hv = parse(cells[col]);
    if (std::isfinite(it) && std::isfinite(hv)) rows.emplace_back(it, hv);
  }
  if (rows.empty())
    throw InputError(file.string(), "", "has no hypervolume value in any iteration");
  return rows;
}

std::string axis_label(const FrontGoal& g) { return g.label + " [" + g.unit + "]"; }

// One axis of a panel: it spans the front's points, and the compared controllers that lie within
// a decade of them (on a linear axis, within the front's span); one farther off would squeeze the
// front into a corner, so it is drawn at the edge and labelled with its value. In log10 on a log
// axis.
struct Axis {
  bool log = true;
  double lo = 0, hi = 1;  // the drawn range (log10 on a log axis)
  double to(double v) const { return log ? std::log10(v) : v; }
  double from(double t) const { return log ? std::pow(10.0, t) : t; }
  bool inside(double v) const { return to(v) >= lo && to(v) <= hi; }
  double clamp(double v) const { return from(std::clamp(to(v), lo, hi)); }
  std::string range() const { return "[" + num(from(lo)) + ":" + num(from(hi)) + "]"; }
};

// Tics of a log axis: gnuplot labels only powers of ten, none at all on a range under a decade,
// so a narrow range gets round values (1, 2, 5 × 10^k, or finer) labelled.
std::string log_tics(const char* axis, const Axis& a) {
  if (!a.log || a.hi - a.lo > 2.5) return std::string("set ") + axis + "tics autofreq\n";
  const std::vector<std::vector<double>> steps = {
      {1, 2, 5}, {1, 1.5, 2, 3, 5, 7}, {1, 1.2, 1.5, 2, 2.5, 3, 4, 5, 6, 7, 8, 9}};
  std::vector<double> tics;
  for (const std::vector<double>& mantissas : steps) {
    tics.clear();
    for (int k = static_cast<int>(std::floor(a.lo)); k <= static_cast<int>(std::ceil(a.hi)); ++k)
      for (double m : mantissas) {
        const double v = m * std::pow(10.0, k);
        if (std::log10(v) >= a.lo && std::log10(v) <= a.hi) tics.push_back(v);
      }
    if (tics.size() >= 3) break;
  }
  std::string s = std::string("set ") + axis + "tics (";
  for (std::size_t i = 0; i < tics.size(); ++i)
    s += (i ? ", '" : "'") + detail::format_number(tics[i], "%g") + "' " + num(tics[i]);
  return s + ")\n";
}

// The axis over [lo, hi] (log10 on a log axis) with a margin either side.
Axis padded(bool log, double lo, double hi) {
  Axis a;
  a.log = log;
  const double pad = log ? std::max(0.1, 0.08 * (hi - lo))
                         : (hi > lo ? 0.08 * (hi - lo) : std::max(1e-12, 0.1 * std::fabs(hi)));
  a.lo = lo - pad;
  a.hi = hi + pad;
  if (!log && lo >= 0 && a.lo < 0) a.lo = 0;  // a goal is not negative
  return a;
}

Axis axis_of(const Front& front, std::size_t g, bool log) {
  Axis a;
  a.log = log;
  double lo = INFINITY, hi = -INFINITY;
  for (const FrontPoint& p : front.points)
    if (std::isfinite(p.goals[g]) && (!log || p.goals[g] > 0)) {
      lo = std::min(lo, a.to(p.goals[g]));
      hi = std::max(hi, a.to(p.goals[g]));
    }
  if (!(lo <= hi)) return a;
  const double reach = log ? 1.0 : std::max(hi - lo, 1e-12 + 0.1 * std::fabs(hi));
  const double flo = lo, fhi = hi;
  for (const FrontCompared& c : front.compared)
    if (std::isfinite(c.goals[g]) && (!log || c.goals[g] > 0)) {
      const double t = a.to(c.goals[g]);
      if (t >= flo - reach && t <= fhi + reach) {
        lo = std::min(lo, t);
        hi = std::max(hi, t);
      }
    }
  return padded(log, lo, hi);
}

// What the soft goals' log10 space and its reference point are, in words.
std::string reference_text(const Front& front) {
  std::string s;
  for (std::size_t k = 0; k < front.soft.size(); ++k) {
    const FrontGoal& g = front.goals[front.soft[k]];
    s += (k ? "; " : "") + g.label + " = 10^" + detail::format_number(front.reference[k]) + " = " +
         detail::format_number(std::pow(10.0, front.reference[k])) + " " + g.unit;
  }
  return s;
}

// Where a panel's text labels go, so that none covers another: each label is a box of one text
// row, its width estimated from its characters, placed at an offset (in character cells, as
// gnuplot's `offset`) from its anchor. The fixed boxes first, then the others from the highest
// marker down (so that labels keep their markers' order); a label whose box would overlap one
// already placed is moved by a row and a fifth at a time, nearest first (below, then above),
// staying inside the panel where it can. Sizes are estimates of the PNG terminal's default font, in
// the panel's pixels: a label a few pixels off is still read, two on one line are not.
constexpr double kLabelChar = 7.5;  // px of a label's character, about, in the PNG terminal

struct LabelBox {
  double fx = 0, fy = 0;  // the anchor, as a fraction of the plot area (0..1 from bottom left)
  std::size_t chars = 0;  // the text's length in characters (UTF-8 continuation bytes not counted)
  bool right = false;     // right-aligned at the anchor (text to its left)
  double dx = 1, dy = 0;  // the wanted offset in character cells
  bool fixed = false;     // placed where asked (the picked point's label)
};

std::size_t text_chars(const std::string& s) {
  std::size_t n = 0;
  for (unsigned char c : s) n += (c & 0xC0) != 0x80;
  return n;
}

// The vertical offsets (in rows) at which the labels do not overlap, in the order given.
std::vector<double> place_labels(const std::vector<LabelBox>& labels, double plot_w,
                                 double plot_h) {
  constexpr double kRow = 16, kChar = kLabelChar;  // px of one text row and one character
  struct Box {
    double x0, x1, y;
  };
  std::vector<Box> placed;
  std::vector<double> rows(labels.size());
  std::vector<std::size_t> order(labels.size());
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
  // By the markers' height, not the labels' wanted one: a label wanted above its marker must not
  // take the place of a higher marker's label.
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    if (labels[a].fixed != labels[b].fixed) return labels[a].fixed;
    return labels[a].fy > labels[b].fy;
  });
  const auto box = [&](const LabelBox& l, double dy) {
    const double x = l.fx * plot_w + l.dx * kChar, w = static_cast<double>(l.chars) * kChar;
    return Box{l.right ? x - w : x, l.right ? x : x + w, l.fy * plot_h + dy * kRow};
  };
  const auto clear_of = [&](const Box& b) {
    for (const Box& o : placed)
      if (b.x0 < o.x1 && o.x0 < b.x1 && std::fabs(b.y - o.y) < 1.05 * kRow) return false;
    return true;
  };
  for (std::size_t i : order) {
    const LabelBox& l = labels[i];
    double dy = l.dy;
    if (!l.fixed) {
      // The wanted offset, then a row and a fifth further each way, below first; inside the
      // panel if possible.
      bool found = false;
      for (int pass = 0; pass < 2 && !found; ++pass)
        for (int k = 0; k <= 12 && !found; ++k) {
          const double step = 1.2 * ((k + 1) / 2) * (k % 2 ? -1 : 1);
          const Box b = box(l, l.dy + step);
          const bool inside = b.y >= 0.5 * kRow && b.y <= plot_h - 0.5 * kRow;
          if ((inside || pass == 1) && clear_of(b)) {
            dy = l.dy + step;
            found = true;
          }
        }
    }
    placed.push_back(box(l, dy));
    rows[i] = dy;
  }
  return rows;
}

}  // namespace

std::vector<Figure> draw_front_figures(const fs::path& run_dir, const Front& front,
                                       FigureFormat fmt) {
  // An empty front (no trial met the hard goals): no point to draw, and a hypervolume that is 0
  // in every iteration, against no reference point. The report says so in words.
  if (front.points.empty()) return {};
  const std::string ext = plot::extension(fmt);
  const std::size_t S = front.soft.size();
  std::ostringstream g;
  g << plot::styles(0);
  int blocks = 0;
  const auto block = [&](const std::string& rows) {
    const std::string name = "$d" + std::to_string(++blocks);
    g << name << " << EOD\n" << rows << "EOD\n";
    return name;
  };

  // The pairwise scatter: one panel per pair of soft goals.
  std::vector<std::pair<std::size_t, std::size_t>> pairs;
  for (std::size_t a = 0; a < S; ++a)
    for (std::size_t b = a + 1; b < S; ++b) pairs.emplace_back(front.soft[a], front.soft[b]);
  const std::size_t cols = std::min<std::size_t>(pairs.size(), 3),
                    rows = (pairs.size() + cols - 1) / cols;
  const int width = cols == 1 ? 1000 : static_cast<int>(620 * cols),
            height = static_cast<int>(640 * rows + 60);
  const std::string scatter = "figures/front-pareto" + ext;
  // Marker colours: the front darkest, the picked point and the compared controllers apart.
  const std::string front_colour = plot::viridis(0.0), picked_colour = plot::viridis(0.6);
  static const int kComparedMarks[] = {5, 9, 13, 11, 15};
  bool any_noise = false, any_infeasible = false, any_noise_pair = false;
  for (const FrontPoint& p : front.points) {
    for (std::size_t s : front.soft) any_noise = any_noise || std::isfinite(floor_at(p, s));
    any_infeasible = any_infeasible || !p.feasible();
  }
  // The pairs that are no trade-off, as front.json lists each point's partners.
  std::vector<std::pair<std::size_t, std::size_t>> noise_pairs;
  for (std::size_t a = 0; a < front.points.size(); ++a)
    for (std::size_t b : front.points[a].within_noise)
      if (a < b) noise_pairs.emplace_back(a, b);
  any_noise_pair = !noise_pairs.empty();

  // A panel's plot area in pixels, about: the panel less the axes' tics and titles, the key
  // below it (8 rows) and the title.
  const double panel_w = static_cast<double>(width) / static_cast<double>(cols) - 110,
               panel_h = static_cast<double>(height - 60) / static_cast<double>(rows) - 8 * 16 - 70;
  g << plot::terminal(fmt, width, height) << "set output " << gp(scatter) << "\n"
    << "set multiplot layout " << rows << "," << cols << " title "
    << gp("Pareto front of the tuned points (" + std::to_string(front.points.size()) +
          " points), pairwise")
    << " font ',13'\nset key below horizontal maxrows 4 box opaque noenhanced font ',9'\n"
    << "set bmargin 8\n";
  std::size_t undrawn = 0;
  for (const auto& [x, y] : pairs) {
    const bool log_x = log_axis(front, x), log_y = log_axis(front, y);
    std::string pts, bars, infeasible, links;
    for (const FrontPoint& p : front.points) {
      const double vx = p.goals[x], vy = p.goals[y];
      if (!std::isfinite(vx) || !std::isfinite(vy)) {
        ++undrawn;
        continue;
      }
      (p.feasible() ? pts : infeasible) += num(vx) + "," + num(vy) + "\n";
      const auto [x0, x1] = band(vx, floor_at(p, x), log_x);
      const auto [y0, y1] = band(vy, floor_at(p, y), log_y);
      bars += num(vx) + "," + num(vy) + "," + num(x0) + "," + num(x1) + "," + num(y0) + "," +
              num(y1) + "\n";
    }
    for (const auto& [a, b] : noise_pairs) {
      const FrontPoint &p = front.points[a], &q = front.points[b];
      if (std::isfinite(p.goals[x]) && std::isfinite(p.goals[y]) && std::isfinite(q.goals[x]) &&
          std::isfinite(q.goals[y]))
        links += num(p.goals[x]) + "," + num(p.goals[y]) + "\n" + num(q.goals[x]) + "," +
                 num(q.goals[y]) + "\n\n";
    }
    g << "unset label\n"
      << (log_x ? "set logscale x\nset format x '%g'\n" : "unset logscale x\nset format x '%g'\n")
      << (log_y ? "set logscale y\nset format y '%g'\n" : "unset logscale y\nset format y '%g'\n")
      << "set xlabel " << gp(axis_label(front.goals[x])) << " noenhanced\nset ylabel "
      << gp(axis_label(front.goals[y])) << " noenhanced\n";
    const Axis ax = axis_of(front, x, log_x), ay = axis_of(front, y, log_y);
    // The panel's labels, as boxes in its plot area (place_labels).
    std::vector<LabelBox> boxes;
    const auto frac = [](const Axis& a, double v) {
      return a.hi > a.lo ? (a.to(v) - a.lo) / (a.hi - a.lo) : 0.5;
    };
    g << "set xrange " << ax.range() << "\nset yrange " << ay.range() << "\n"
      << log_tics("x", ax) << log_tics("y", ay);
    std::string cmd = "plot ";
    if (any_noise && !bars.empty())
      cmd += block(bars) + " using 1:2:3:4:5:6 with xyerrorbars pt 0 lw 1 lc rgb 'gray55' title " +
             gp("noise floor (band of one relative spread)") + ", ";
    if (!links.empty())
      cmd += block(links) + " using 1:2 with lines dt 2 lw 1.5 lc rgb 'gray30' title " +
             gp("within one's noise floor on every goal: not a trade-off") + ", ";
    if (!pts.empty())
      cmd += block(pts) + " using 1:2 with points pt 7 ps 1.1 lc rgb '" + front_colour +
             "' title " + gp("front: tuned, non-dominated points") + ", ";
    if (!infeasible.empty())
      cmd += block(infeasible) + " using 1:2 with points pt 2 ps 1.1 lc rgb '" + front_colour +
             "' title 'infeasible point', ";
    {  // the points are not empty: one of them is picked
      const FrontPoint& p = front.points[front.picked];
      if (std::isfinite(p.goals[x]) && std::isfinite(p.goals[y])) {
        const std::string text = "picked (" + front.rule + "), #" + std::to_string(front.picked);
        cmd += block(num(p.goals[x]) + "," + num(p.goals[y]) + "\n") +
               " using 1:2 with points pt 6 ps 3 lw 2.5 lc rgb '" + picked_colour + "' title " +
               gp(text) + ", ";
        g << "set label " << gp("picked") << " at " << num(p.goals[x]) << "," << num(p.goals[y])
          << " offset 1.6,-1.2 textcolor rgb '" << picked_colour << "' front\n";
        boxes.push_back({frac(ax, p.goals[x]), frac(ay, p.goals[y]), 6, false, 1.6, -1.2, true});
      }
    }
    struct Pending {
      std::string text;
      double px, py;
      bool right;
    };
    std::vector<Pending> pending;
    for (std::size_t c = 0; c < front.compared.size(); ++c) {
      const FrontCompared& k = front.compared[c];
      const double vx = k.goals[x], vy = k.goals[y];
      const std::string name = (k.role == "baseline" ? "job's gains: " : "") + k.label +
                               (k.feasible ? "" : " (infeasible)");
      if (!std::isfinite(vx) || !std::isfinite(vy)) continue;
      const std::string colour = plot::viridis(
          0.25 + 0.6 * static_cast<double>(c) / std::max<std::size_t>(1, front.compared.size()));
      // Off the panel's scale: at its edge, with its values in the label.
      const bool off = !ax.inside(vx) || !ay.inside(vy);
      const double px = off ? ax.clamp(vx) : vx, py = off ? ay.clamp(vy) : vy;
      const std::string text = off ? name + " (off scale: " + detail::format_number(vx) + ", " +
                                         detail::format_number(vy) + ")"
                                   : name;
      cmd += block(num(px) + "," + num(py) + "\n") + " using 1:2 with points pt " +
             std::to_string(kComparedMarks[c % 5] - (off ? 1 : 0)) + " ps 1.8 lc rgb '" + colour +
             "' title " + gp(name) + ", ";
      // Each label a little above and right of its marker (right-aligned at the right edge, and
      // wherever the text would run past it); place_labels then moves apart those that would
      // cover one another, keeping their markers' order. One off the scale sits on its marker's
      // row, beside it, so that several at one edge keep that order too.
      const bool right =
          (off && ax.to(px) >= ax.hi) ||
          frac(ax, px) * panel_w + (static_cast<double>(text_chars(text)) + 1) * kLabelChar >
              panel_w;
      const bool top = off && ay.to(py) >= ay.hi;
      boxes.push_back({frac(ax, px), frac(ay, py), text_chars(text), right, right ? -1.0 : 1.0,
                       top   ? -1.3
                       : off ? 0.0
                             : 0.9,
                       false});
      pending.push_back({text, px, py, right});
    }
    const std::vector<double> rows_at = place_labels(boxes, panel_w, panel_h);
    for (std::size_t k = 0; k < pending.size(); ++k) {
      const Pending& l = pending[k];
      g << "set label " << gp(l.text) << " at " << num(l.px) << "," << num(l.py)
        << (l.right ? " right offset -1," : " offset 1,")
        << num(rows_at[boxes.size() - pending.size() + k]) << " noenhanced front\n";
    }
    g << cmd.substr(0, cmd.size() - 2) << "\n";
  }
  g << "unset multiplot\nunset label\nunset logscale x\nunset logscale y\nset format x '%g'\n"
       "set format y '%g'\nset autoscale\nunset bmargin\nset xtics autofreq\nset ytics autofreq\n";
  std::string caption =
      "Each panel shows two soft goals of the points the search kept (a tuned front: the best "
      "trade-offs this run found, not a proven optimum), with the picked point (gains.json) "
      "circled and the compared controllers labelled. Axes are logarithmic where every value is "
      "positive. Grey bars span a point's noise floor where the run measured it (one relative "
      "spread across its perturbed re-runs, centred on the value)";
  caption += any_noise_pair ? "; dashed links join points whose difference on every soft goal "
                              "is within the noise floor of one of them (the larger of the "
                              "two): their difference is noise, not a trade-off."
                            : "; no two points differ by less than the noise floor of one of "
                              "them on every soft goal.";
  if (!any_noise) caption += " No point's noise floor was measured.";
  if (any_infeasible) caption += " Crosses are points that violate a hard goal.";
  caption +=
      " A compared controller far off the front's scale is drawn at the panel's edge "
      "(open marker), its values in its label.";
  if (undrawn)
    caption += " " + std::to_string(undrawn) +
               " point-panel(s) with a diverged or missing goal value are not drawn.";
  std::vector<Figure> figures{{scatter, "Pareto front", caption}};

  // The hypervolume of the front per iteration.
  const std::vector<std::pair<double, double>> hv = hypervolume_history(run_dir / "history.csv");
  std::string rows_text;
  for (const auto& [it, v] : hv) rows_text += num(it) + "," + num(v) + "\n";
  std::string ref = "(";
  for (std::size_t k = 0; k < S; ++k) ref += (k ? ", " : "") + num(front.reference[k]);
  ref += ")";
  const std::string hv_file = "figures/front-hypervolume" + ext;
  // The unit: decades to the power of the soft goals' count.
  static const char* const kPowers[] = {"", "", "²", "³", "⁴", "⁵", "⁶", "⁷", "⁸", "⁹"};
  const std::string decades =
      S < 10 ? std::string("decade") + kPowers[S] : "decade^{" + std::to_string(S) + "}";
  // Whole iterations on the x axis, about ten tics.
  const double last = hv.back().first;
  const std::string xstep = num(std::max(1.0, std::ceil(last / 10)));
  const std::string data = block(rows_text);
  g << plot::terminal(fmt, 1000, 600) << "set output " << gp(hv_file) << "\nset title "
    << gp("Hypervolume of the front per iteration; reference point " + ref +
          " in log10 of the soft goals")
    << " font ',12' noenhanced\nset xlabel 'iteration'\nset ylabel "
    << gp("hypervolume [" + decades + "]") << "\nset xtics " << xstep
    << "\nset key inside right bottom box opaque\nplot " << data
    << " using 1:2 with linespoints pt 7 lw 2 lc rgb '" << front_colour << "' title "
    << gp("front after each iteration") << "\nunset title\nset xtics autofreq\nset key default\n";
  figures.push_back(
      {hv_file, "Hypervolume",
       "The hypervolume the front dominates after each iteration (history.csv), measured on "
       "log10 of each soft goal against the reference point " +
           ref + " (" + reference_text(front) +
           "). A flat stretch means those iterations added no trade-off the front did not have. "
           "Final front: " +
           detail::format_number(front.hypervolume, "%.6g") + "."});

  write_file_atomic(run_dir / "figures" / "front.gp", g.str());
  run_gnuplot(run_dir, "figures/front.gp");
  return figures;
}

}  // namespace ftc::tune::report_detail

namespace ftc::tune {

std::filesystem::path draw_held_out_front(const Front& front, const std::filesystem::path& dir,
                                          FigureFormat fmt) {
  using namespace report_detail;
  if (!front.held_out || front.points.empty() || front.soft.size() < 2) return {};
  const std::size_t x = front.soft[0], y = front.soft[1];
  const std::string ext = plot::extension(fmt);
  const std::filesystem::path figure = dir / ("front-held-out" + ext);
  // Both clouds and the compared controllers set the axes: log where every value is positive.
  std::vector<double> xs, ys;
  for (const FrontPoint& p : front.points) {
    for (const std::vector<double>* g : {&p.goals, &p.in_sample})
      if (g->size() > std::max(x, y) && std::isfinite((*g)[x]) && std::isfinite((*g)[y])) {
        xs.push_back((*g)[x]);
        ys.push_back((*g)[y]);
      }
  }
  for (const FrontCompared& c : front.compared)
    if (std::isfinite(c.goals[x]) && std::isfinite(c.goals[y])) {
      xs.push_back(c.goals[x]);
      ys.push_back(c.goals[y]);
    }
  if (xs.empty()) return {};
  const auto axis = [](const std::vector<double>& v) {
    Axis a;
    a.log = std::all_of(v.begin(), v.end(), [](double t) { return t > 0; });
    double lo = INFINITY, hi = -INFINITY;
    for (double t : v) {
      lo = std::min(lo, a.to(t));
      hi = std::max(hi, a.to(t));
    }
    return padded(a.log, lo, hi);
  };
  const Axis ax = axis(xs), ay = axis(ys);
  const std::string front_colour = plot::viridis(0.0), picked_colour = plot::viridis(0.6);
  std::string links, in_sample, kept, dropped;
  std::size_t on = 0;
  for (const FrontPoint& p : front.points) {
    const bool held = std::isfinite(p.goals[x]) && std::isfinite(p.goals[y]);
    const bool ran = p.in_sample.size() > std::max(x, y) && std::isfinite(p.in_sample[x]) &&
                     std::isfinite(p.in_sample[y]);
    if (ran) in_sample += num(p.in_sample[x]) + "," + num(p.in_sample[y]) + "\n";
    if (held) (p.dominated ? dropped : kept) += num(p.goals[x]) + "," + num(p.goals[y]) + "\n";
    if (held && ran)
      links += num(p.in_sample[x]) + "," + num(p.in_sample[y]) + "\n" + num(p.goals[x]) + "," +
               num(p.goals[y]) + "\n\n";
    on += p.dominated ? 0 : 1;
  }
  std::ostringstream g;
  int blocks = 0;
  const auto block = [&](const std::string& rows) {
    const std::string name = "$d" + std::to_string(++blocks);
    g << name << " << EOD\n" << rows << "EOD\n";
    return name;
  };
  const FrontHeldOut& h = *front.held_out;
  g << plot::styles(0) << plot::terminal(fmt, 1000, 700) << "set output "
    << gp(figure.filename().string()) << "\nset title "
    << gp("The run's front in sample and on " + std::to_string(h.count) +
          " held-out members (seed " + std::to_string(h.seed) + "): " + std::to_string(on) +
          " of " + std::to_string(front.points.size()) + " points stay on it")
    << " font ',12' noenhanced\nset key below horizontal maxrows 3 box opaque noenhanced "
       "font ',9'\nset bmargin 7\n"
    << (ax.log ? "set logscale x\n" : "unset logscale x\n")
    << (ay.log ? "set logscale y\n" : "unset logscale y\n")
    << "set format x '%g'\nset format y '%g'\nset xlabel " << gp(axis_label(front.goals[x]))
    << " noenhanced\nset ylabel " << gp(axis_label(front.goals[y])) << " noenhanced\nset xrange "
    << ax.range() << "\nset yrange " << ay.range() << "\n"
    << log_tics("x", ax) << log_tics("y", ay);
  std::string cmd = "plot ";
  if (!links.empty())
    cmd += block(links) + " using 1:2 with lines lw 1 lc rgb 'gray60' title " +
           gp("a point in sample to held out") + ", ";
  if (!in_sample.empty())
    cmd += block(in_sample) + " using 1:2 with points pt 6 ps 1.1 lc rgb 'gray35' title " +
           gp("in sample (the run's front)") + ", ";
  if (!kept.empty())
    cmd += block(kept) + " using 1:2 with points pt 7 ps 1.1 lc rgb '" + front_colour + "' title " +
           gp("held out, still on the front") + ", ";
  if (!dropped.empty())
    cmd += block(dropped) + " using 1:2 with points pt 2 ps 1.2 lc rgb '" + front_colour +
           "' title " + gp("held out, off the front (dominated or infeasible)") + ", ";
  if (on > 0) {
    const FrontPoint& k = front.points[front.picked];
    if (std::isfinite(k.goals[x]) && std::isfinite(k.goals[y]))
      cmd += block(num(k.goals[x]) + "," + num(k.goals[y]) + "\n") +
             " using 1:2 with points pt 6 ps 3 lw 2.5 lc rgb '" + picked_colour + "' title " +
             gp("held-out knee, #" + std::to_string(front.picked)) + ", ";
  }
  static const int kComparedMarks[] = {5, 9, 13, 11, 15};
  for (std::size_t c = 0; c < front.compared.size(); ++c) {
    const FrontCompared& k = front.compared[c];
    if (!std::isfinite(k.goals[x]) || !std::isfinite(k.goals[y])) continue;
    const std::string colour = plot::viridis(
        0.25 + 0.6 * static_cast<double>(c) / std::max<std::size_t>(1, front.compared.size()));
    cmd += block(num(k.goals[x]) + "," + num(k.goals[y]) + "\n") + " using 1:2 with points pt " +
           std::to_string(kComparedMarks[c % 5]) + " ps 1.8 lc rgb '" + colour + "' title " +
           gp((k.role == "baseline" ? "job's gains: " : "") + k.label +
              (k.feasible ? "" : " (infeasible)") + ", held out") +
           ", ";
  }
  g << cmd.substr(0, cmd.size() - 2) << "\n";
  write_file_atomic(dir / ("front-held-out.gp"), g.str());
  run_gnuplot(dir, "front-held-out.gp");
  return figure;
}

}  // namespace ftc::tune
