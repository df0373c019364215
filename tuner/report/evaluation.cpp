#include "ftc/tune/report/evaluation.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <sstream>

#include "ftc/tune/io/files.hpp"
#include "ftc/tune/job/ensemble.hpp"
#include "io/text.hpp"
#include "report/gnuplot.hpp"

namespace ftc::tune {

namespace fs = std::filesystem;

namespace {

// An ECDF of more points than this is thinned: the eye cannot see them and the script grows.
constexpr std::size_t kMaxCdfPoints = 2000;

}  // namespace

fs::path draw_evaluation(const EvaluationResult& r, const fs::path& dir, FigureFormat format) {
  const bool include = r.job.ensemble && r.job.ensemble->unrecoverable == Unrecoverable::include;
  const fs::path figure = dir / (std::string("evaluation") + plot::extension(format));
  std::ostringstream g;
  // Each controller in its type's style (the report's): the job's and its compare entries by
  // type, the first gains file as the tuned controller.
  std::vector<plot::Series> as_series;
  bool first_file = true;
  for (const EvaluatedController& c : r.controllers) {
    const bool file = c.source != "job" && c.source != "compare";
    as_series.push_back({c.label, "", file && first_file, sim::to_string(c.controller.type)});
    if (file) first_file = false;
  }
  const std::vector<int> style = plot::controller_style_list(as_series);
  g << plot::styles(0) << plot::controller_styles() << plot::terminal(format, 1300, 560)
    << "set output " << plot::gp(figure.filename().string()) << "\n";
  std::size_t left_out = 0;  // unrecoverable members the aggregates leave out
  if (!include && !r.controllers.empty())
    for (const MemberResult& m : r.controllers.front().members) left_out += !m.recoverable;
  std::vector<std::size_t> finite_counts, diverged_counts, zero_counts;
  for (std::size_t c = 0; c < r.controllers.size(); ++c) {
    std::vector<double> v;
    std::size_t diverged = 0, zero = 0;
    for (const MemberResult& m : r.controllers[c].members) {
      if (!(m.recoverable || include)) continue;
      if (!std::isfinite(m.objective))
        ++diverged;
      else if (m.objective > 0)
        v.push_back(m.objective);
      else
        ++zero;  // an empty window (its fault starts after the end): no place on a log axis
    }
    std::sort(v.begin(), v.end());
    // The CDF counts diverged members too (they sit beyond the right edge), so a controller
    // that diverges often never reaches 1.
    const double n = static_cast<double>(v.size() + diverged + zero);
    g << "$cdf" << c << " << EOD\n";
    const std::size_t step = std::max<std::size_t>(1, v.size() / kMaxCdfPoints);
    for (std::size_t k = 0; k < v.size(); ++k)
      if (k % step == 0 || k + 1 == v.size())
        g << detail::format_number(v[k], "%.9g") << ","
          << detail::format_number(static_cast<double>(zero + k + 1) / n, "%.6g") << "\n";
    g << "EOD\n$box" << c << " << EOD\n";
    for (double x : v) g << detail::format_number(x, "%.9g") << "\n";
    g << "EOD\n";
    finite_counts.push_back(v.size());
    diverged_counts.push_back(diverged);
    zero_counts.push_back(zero);
  }
  const sim::MetricField& metric = *r.job.objective.metric;
  const std::string what =
      sim::plain_label(metric) + " of a member [" + std::string(metric.unit) + "] (log scale)";
  g << "set multiplot layout 1,2 title "
    << plot::gp("Out of sample: " + r.job.name + ", " + std::to_string(r.job.scenarios.size()) +
                (r.job.scenarios.size() == 1 ? " listed scenario + " : " listed scenarios + ") +
                std::to_string(r.count) + " members (seed " + std::to_string(r.seed) + ")" +
                (left_out > 0 ? "; " + std::to_string(left_out) +
                                    " unrecoverable members left out (no gains can control them)"
                              : std::string()))
    << " font ',13'\n"
    << "set logscale x\nset format x '%.2g'\nset xlabel " << plot::gp(what)
    << "\nset ylabel 'fraction of members at or below (1 = all)'\nset yrange [0:1.02]\n"
    << "set key bottom right inside opaque box noenhanced\nplot ";
  for (std::size_t c = 0; c < r.controllers.size(); ++c) {
    std::string title = r.controllers[c].label;
    if (diverged_counts[c] > 0) title += " (" + std::to_string(diverged_counts[c]) + " diverged)";
    if (zero_counts[c] > 0) title += " (" + std::to_string(zero_counts[c]) + " at 0, not drawn)";
    g << (c ? ", \\\n     " : "") << "$cdf" << c << " using 1:2 with steps ls " << style[c]
      << " lw 2 title " << plot::gp(title);
  }
  g << "\nunset logscale x\nset format x '%g'\nset rmargin 10\nunset xlabel\nset ylabel "
    << plot::gp(what) << "\nset logscale y\nset format y '%.2g'\nset autoscale y\nset xrange [-0.6:"
    << static_cast<double>(r.controllers.size()) - 0.4
    << "]\nset xtics noenhanced rotate by -20 left (";
  for (std::size_t c = 0; c < r.controllers.size(); ++c)
    g << (c ? ", " : "") << plot::gp(r.controllers[c].label) << " " << c;
  g << ")\nset style fill solid 0.25 border -1\nset style boxplot outliers pointtype 7\n"
       "set style data boxplot\nunset key\nplot ";
  bool any = false;
  for (std::size_t c = 0; c < r.controllers.size(); ++c) {
    if (finite_counts[c] == 0) continue;
    g << (any ? ", \\\n     " : "") << "$box" << c << " using (" << c << "):1 ls " << style[c]
      << " ps 0.4";
    any = true;
  }
  if (!any) g << "NaN notitle";
  g << "\nunset multiplot\n";
  write_file_atomic(dir / "evaluation.gp", g.str());
  run_gnuplot(dir, "evaluation.gp");
  return figure;
}

}  // namespace ftc::tune
