#include "ftc/tune/report/landscape.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <sstream>

#include "ftc/sim/controller_config.hpp"
#include "ftc/tune/io/files.hpp"
#include "ftc/tune/problem/problem.hpp"
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

// The unit of a tunable controller field, as the controllers' headers give them (laws.hpp):
// X1 in rad, X2 in rad/s, the surfaces sF and sPI in rad/s² (NFTSMC's s in rad), K in rad/s³.
// The plants' states are angles in rad for the spacecraft, the arm and the hexarotor alike.
// Gains that multiply a fractional power carry its exponent.
std::string parameter_unit(const std::string& name, sim::ControllerType type) {
  if (name == "Kp" || name == "alpha" || name == "alpha1" || name == "alpha2")
    return "dimensionless";
  if (name == "Ki") return "1/s";
  if (name == "switching_gain") return type == sim::ControllerType::nftsmc ? "rad/s²" : "rad/s³";
  if (name == "zeta" || name == "ka0") return "rad/s³";
  if (name == "theta") return type == sim::ControllerType::nftsmc ? "1/rad" : "s²/rad";
  if (name == "c1") return "rad^(1−α1)/s²";
  if (name == "c2") return "rad^(1−α2)·s^(α2−2)";
  if (name == "sigma1") return "rad^(1−α)";
  if (name == "sigma2") return "rad^(1−p/q)·s^(p/q)";
  if (name == "lambda") return "s²";
  if (name == "weight_rate") return "1/s²";
  if (name == "width") return "rad and rad/s, as the state";
  return "";
}

}  // namespace

LandscapeResult compute_landscape(const Job& job_in, const fs::path& out_dir,
                                  const LandscapeOptions& options, BatchEvaluator& evaluator) {
  if (!job_in.tuning)
    throw InputError(job_in.name, "/tuning", "is required: it gives the parameters' bounds");
  std::vector<std::string> params = options.params;
  if (params.empty())
    for (const ParameterBounds& b : job_in.tuning->parameters)
      if (params.size() < 2) params.push_back(b.name);
  if (params.size() != 2 || params[0] == params[1])
    throw InputError("--params", "",
                     "needs two different tuned parameters (the job tunes " +
                         std::to_string(job_in.tuning->parameters.size()) + ")");
  if (options.n1 < 2 || options.n2 < 2 || options.n1 > 1000 || options.n2 > 1000)
    throw InputError("--grid", "", "needs 2..1000 points per parameter");

  // A job tuning exactly the two parameters, everything else at the job's values.
  Job job = job_in;
  std::vector<ParameterBounds> bounds;
  for (const std::string& p : params) {
    auto it = std::find_if(job_in.tuning->parameters.begin(), job_in.tuning->parameters.end(),
                           [&](const ParameterBounds& b) { return b.name == p; });
    if (it == job_in.tuning->parameters.end())
      throw InputError("--params", "", p + " is not under tuning.parameters of the job");
    bounds.push_back(*it);
  }
  // The unplotted tuned parameters held at the given values (the tuned ones, by default in the
  // CLI), else at the job's.
  LandscapeResult r;
  for (const ParameterBounds& b : job_in.tuning->parameters) {
    if (b.name == params[0] || b.name == params[1]) continue;
    const sim::ControllerField* f = sim::find_controller_field(b.name);
    if (!f) continue;
    double v = job.controller.*(f->member);
    for (const auto& [name, value] : options.fixed)
      if (name == b.name) v = value;
    job.controller.*(f->member) = v;
    r.fixed.emplace_back(b.name, v);
  }
  r.fixed_source = options.fixed_source;
  job.tuning->parameters = bounds;
  const TuningProblem problem(job);
  const std::size_t i0 = problem.space().names[0] == params[0] ? 0 : 1;  // problem orders by field

  // Evenly spaced in the coordinate the optimiser searches: the value, or its log.
  const auto at = [](const ParameterBounds& b, int i, int n) {
    const double f = static_cast<double>(i) / (n - 1);
    if (i == n - 1) return b.upper;  // exactly, whatever the rounding on the way
    return b.scale == Scale::log ? b.lower * std::pow(b.upper / b.lower, f)
                                 : b.lower + (b.upper - b.lower) * f;
  };
  std::vector<Decision> grid;
  for (int a = 0; a < options.n1; ++a)
    for (int b = 0; b < options.n2; ++b) {
      const double v0 = at(bounds[0], a, options.n1);
      const double v1 = at(bounds[1], b, options.n2);
      grid.push_back(i0 == 0 ? Decision{v0, v1} : Decision{v1, v0});
    }
  std::vector<sim::ControllerConfig> controllers;
  controllers.reserve(grid.size());
  for (const Decision& x : grid) controllers.push_back(problem.controller_with(x));
  // A block at a time (each still one parallel batch, large enough to keep every core busy),
  // so that a long landscape shows its progress; results are placed by index as before.
  std::vector<CandidateOutcome> outcomes;
  outcomes.reserve(controllers.size());
  const std::size_t block =
      std::max<std::size_t>(64, 16 * static_cast<std::size_t>(evaluator.concurrency()));
  for (std::size_t begin = 0; begin < controllers.size(); begin += block) {
    const std::size_t n = std::min(block, controllers.size() - begin);
    std::vector<CandidateOutcome> part = problem.evaluate(
        std::span<const sim::ControllerConfig>(controllers.data() + begin, n), evaluator);
    for (CandidateOutcome& c : part) outcomes.push_back(std::move(c));
    if (options.progress)
      options.progress(static_cast<std::int64_t>(begin + n),
                       static_cast<std::int64_t>(controllers.size()));
  }

  r.params = params;
  r.simulations = static_cast<std::int64_t>(controllers.size() * problem.scenarios());
  r.best_objective = std::numeric_limits<double>::infinity();
  double worst_objective = 0.0;
  std::string csv = params[0] + "," + params[1] + ",objective,fitness,diverged\n";
  char buf[160];
  for (std::size_t k = 0; k < grid.size(); ++k) {
    const Evaluation& e = outcomes[k].evaluation;
    const double p0 = grid[k][i0], p1 = grid[k][1 - i0];
    std::snprintf(buf, sizeof buf, "%.9g,%.9g,%.9g,%.9g,%d\n", p0, p1,
                  std::isfinite(e.objective) ? e.objective : NAN, e.fitness, e.diverged ? 1 : 0);
    csv += buf;
    if ((k + 1) % static_cast<std::size_t>(options.n2) == 0) csv += "\n";  // gnuplot grid rows
    if (e.objective < r.best_objective) {
      r.best_objective = e.objective;
      r.best = {p0, p1};
    }
    if (std::isfinite(e.objective)) worst_objective = std::max(worst_objective, e.objective);
  }
  fs::create_directories(out_dir);
  r.csv = out_dir / "landscape.csv";
  write_file_atomic(r.csv, csv);

  r.figure = out_dir / (std::string("landscape") + plot::extension(options.format));
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
  double least_excess = std::numeric_limits<double>::infinity();
  for (const CandidateOutcome& o : outcomes) {
    const double x = o.evaluation.objective / r.best_objective - 1;
    if (std::isfinite(x) && x > 0) least_excess = std::min(least_excess, x);
  }
  // Values within the run's noise floor of the lowest are not told apart: they share the
  // colour of the floor. Without a noise floor, the lowest point takes the colour of a tenth of
  // the smallest positive excess.
  const bool have_noise = options.noise_floor > 0 && std::isfinite(options.noise_floor);
  const double floor_excess = have_noise                    ? options.noise_floor
                              : std::isfinite(least_excess) ? least_excess / 10
                                                            : 1e-12;
  const double most_excess = std::max(worst_objective / r.best_objective - 1, 10 * floor_excess);
  const std::string best_text = detail::format_number(r.best_objective, "%.17g");
  const std::string excess = "(($3/" + best_text + " - 1) > " +
                             detail::format_number(floor_excess, "%.17g") + " ? ($3/" + best_text +
                             " - 1) : " + detail::format_number(floor_excess, "%.17g") + ")";
  std::string fixed_text;
  for (const auto& [name, value] : r.fixed)
    fixed_text +=
        (fixed_text.empty() ? "" : ", ") + name + " = " + detail::format_number(value, "%.5g");
  const std::string title =
      objective_label(job_in) + " of " + job.name + " over " + params[0] + " and " + params[1] +
      "\nlowest on the grid " + detail::format_number(r.best_objective, "%.7g") + " " +
      std::string(job.objective.metric->unit) + " at " + params[0] + " = " +
      detail::format_number(r.best[0], "%.5g") + ", " + params[1] + " = " +
      detail::format_number(r.best[1], "%.5g") +
      (fixed_text.empty() ? std::string()
                          : "\n" + fixed_text + " held fixed (" + r.fixed_source + ")");
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
    << plot::gp(label(1)) << " noenhanced\nset xrange [" << range(0, options.n1)
    << "]\nset yrange [" << range(1, options.n2)
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
      for (const auto& [name, value] : r.fixed) {
        const int k = col(name);
        const double v = k <= static_cast<int>(cols.size()) ? cell(k) : NAN;
        on = on && std::abs(v - value) <= 1e-9 * std::max(1.0, std::abs(value));
      }
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
    << axis_end(0, r.best[0]) << "," << axis_end(1, r.best[1]) << "\ne\n";
  write_file_atomic(out_dir / "landscape.gp", g.str());
  run_gnuplot(out_dir, "landscape.gp");
  return r;
}

}  // namespace ftc::tune
