// The objective on a grid over two tuned parameters (run/landscape.hpp).
#include "ftc/tune/run/landscape.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <span>

#include "ftc/sim/controller_config.hpp"
#include "ftc/sim/input_error.hpp"
#include "ftc/tune/problem/problem.hpp"
#include "ftc/tune/run/memory_budget.hpp"

namespace ftc::tune {

Landscape evaluate_landscape(const Job& job_in, const LandscapeGrid& options,
                             BatchEvaluator& evaluator) {
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

  // Memory by design: every grid point keeps its outcome until the landscape is drawn.
  const double points = static_cast<double>(options.n1) * static_cast<double>(options.n2);
  check_memory_need(estimated_scoring_bytes(job_in, points, false), memory_budget_bytes(),
                    "--grid", "a landscape of " +
                        std::to_string(static_cast<long long>(options.n1) * options.n2) + " points");
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
  Landscape r;
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
  r.bounds = bounds;
  r.n1 = options.n1;
  r.n2 = options.n2;
  r.simulations = static_cast<std::int64_t>(controllers.size() * problem.scenarios());
  r.best_objective = std::numeric_limits<double>::infinity();
  for (std::size_t k = 0; k < grid.size(); ++k) {
    const Evaluation& e = outcomes[k].evaluation;
    const double p0 = grid[k][i0], p1 = grid[k][1 - i0];
    r.points.push_back({p0, p1, e.objective, e.fitness, e.diverged});
    if (e.objective < r.best_objective) {
      r.best_objective = e.objective;
      r.best = {p0, p1};
    }
    if (std::isfinite(e.objective)) r.worst_objective = std::max(r.worst_objective, e.objective);
  }
  r.least_excess = std::numeric_limits<double>::infinity();
  for (const LandscapePoint& p : r.points) {
    const double x = p.objective / r.best_objective - 1;
    if (std::isfinite(x) && x > 0) r.least_excess = std::min(r.least_excess, x);
  }
  return r;
}

std::string landscape_csv(const Landscape& l) {
  std::string csv = l.params[0] + "," + l.params[1] + ",objective,fitness,diverged\n";
  char buf[160];
  for (std::size_t k = 0; k < l.points.size(); ++k) {
    const LandscapePoint& p = l.points[k];
    std::snprintf(buf, sizeof buf, "%.9g,%.9g,%.9g,%.9g,%d\n", p.p0, p.p1,
                  std::isfinite(p.objective) ? p.objective : NAN, p.fitness, p.diverged ? 1 : 0);
    csv += buf;
    if ((k + 1) % static_cast<std::size_t>(l.n2) == 0) csv += "\n";  // gnuplot grid rows
  }
  return csv;
}

}  // namespace ftc::tune
