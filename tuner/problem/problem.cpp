#include "ftc/tune/problem/problem.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

#include "ftc/runtime/json_reader.hpp"

namespace ftc::tune {

double aggregate_objective(const ObjectiveConfig& objective, std::span<const sim::Metrics> runs) {
  double acc = 0.0;
  for (const sim::Metrics& m : runs) {
    const double v = m.objective(objective.metric);
    acc = objective.aggregate == Aggregate::mean ? acc + v : std::max(acc, v);
  }
  if (objective.aggregate == Aggregate::mean && !runs.empty())
    acc /= static_cast<double>(runs.size());
  return acc;
}

double fitness_of(double objective) {
  if (!std::isfinite(objective) || objective < 0) return 0.0;
  if (objective == 0.0) return std::numeric_limits<double>::infinity();
  return 1.0 / objective;
}

TuningProblem::TuningProblem(Job job) : job_(std::make_shared<const Job>(std::move(job))) {
  throw_if_errors("job " + job_->name, job_->validate());
  plant_ = sim::make_plant(job_->plant);
  if (!job_->tuning) return;
  for (const ParameterBounds& b : job_->tuning->parameters) {
    const sim::ControllerField* f = sim::find_controller_field(b.name);
    space_.names.push_back(b.name);
    space_.lower.push_back(b.lower);
    space_.upper.push_back(b.upper);
    members_.push_back(f->member);  // validate() made sure the field exists and is tunable
  }
}

sim::ControllerConfig TuningProblem::controller_for(std::span<const double> x) const {
  sim::ControllerConfig c = job_->controller;
  for (std::size_t j = 0; j < members_.size(); ++j) c.*members_[j] = x[j];
  return c;
}

sim::SimulationOptions TuningProblem::simulation_options(std::size_t scenario,
                                                         std::int64_t record_every) const {
  const sim::Scenario& s = job_->scenarios.at(scenario);
  sim::SimulationOptions o;
  o.window = job_->objective.window;
  o.record_every = record_every;
  std::vector<double> cuts;
  for (const sim::Fault& f : s.faults)
    if (f.onset > 0 && f.onset < s.duration) cuts.push_back(f.onset);
  std::sort(cuts.begin(), cuts.end());
  cuts.erase(std::unique(cuts.begin(), cuts.end()), cuts.end());
  double start = 0.0;
  for (double c : cuts) {
    o.extra_windows.push_back({start, c});
    start = c;
  }
  o.extra_windows.push_back({start, s.duration});
  return o;
}

sim::SimulationResult TuningProblem::simulate(const sim::ControllerConfig& controller,
                                              std::size_t scenario,
                                              std::int64_t record_every) const {
  return plant_->simulate(controller, job_->scenarios.at(scenario),
                          simulation_options(scenario, record_every));
}

std::vector<SimulationTask> TuningProblem::tasks(std::size_t candidates) const {
  std::vector<SimulationTask> t;
  t.reserve(candidates * scenarios());
  for (std::size_t c = 0; c < candidates; ++c)
    for (std::size_t s = 0; s < scenarios(); ++s) t.push_back({c, s});
  return t;
}

Evaluation TuningProblem::score(std::vector<sim::Metrics> per_scenario) const {
  Evaluation e;
  e.scenarios = std::move(per_scenario);
  for (const sim::Metrics& m : e.scenarios) e.diverged = e.diverged || m.diverged;
  e.objective = aggregate_objective(job_->objective, e.scenarios);
  e.fitness = e.diverged ? 0.0 : fitness_of(e.objective);
  return e;
}

std::vector<CandidateOutcome> TuningProblem::evaluate(
    std::span<const sim::ControllerConfig> controllers, BatchEvaluator& evaluator,
    std::int64_t record_every) const {
  const std::vector<SimulationTask> t = tasks(controllers.size());
  std::vector<TaskResult> results = evaluator.run(*this, {controllers, t, record_every});
  const std::size_t S = scenarios();
  std::vector<CandidateOutcome> out(controllers.size());
  for (std::size_t i = 0; i < controllers.size(); ++i) {
    std::vector<sim::Metrics> per;
    per.reserve(S);
    for (std::size_t s = 0; s < S; ++s) {
      TaskResult& r = results[i * S + s];
      per.push_back(std::move(r.metrics));
      if (record_every > 0) out[i].trajectories.push_back(std::move(r.trajectory));
      if (out[i].error.empty() && !r.error.empty()) out[i].error = r.error;
    }
    out[i].evaluation = score(std::move(per));
    if (!out[i].error.empty()) {
      out[i].evaluation.objective = std::numeric_limits<double>::infinity();
      out[i].evaluation.fitness = 0.0;
    }
  }
  return out;
}

double TuningProblem::objective(std::span<const double> x, const ObjectiveOptions& options) const {
  if (x.size() != space_.dimension()) {
    std::string names;
    for (const std::string& n : space_.names) names += (names.empty() ? "" : ", ") + n;
    throw InputError("objective", "",
                     "x has " + std::to_string(x.size()) + " values, the problem " +
                         std::to_string(space_.dimension()) + " (" + names + ")");
  }
  std::vector<FieldError> errs;
  for (std::size_t j = 0; j < x.size(); ++j)
    if (!(x[j] >= space_.lower[j] && x[j] <= space_.upper[j]))
      errs.push_back({std::string("/").append(std::to_string(j)),
                      space_.names[j] + " = " + json_io::number_text(x[j], 17) +
                          " is outside its bounds [" + json_io::number_text(space_.lower[j]) +
                          ", " + json_io::number_text(space_.upper[j]) + "]"});
  throw_if_errors("objective", std::move(errs));
  SerialEvaluator serial;
  const sim::ControllerConfig c = controller_for(x);
  const CandidateOutcome o = evaluate(std::span<const sim::ControllerConfig>(&c, 1), serial)[0];
  if (!o.error.empty()) throw InputError("objective", "", o.error);
  const double v =
      o.evaluation.diverged ? std::numeric_limits<double>::infinity() : o.evaluation.objective;
  if (!std::isfinite(v) && options.diverged_penalty) return *options.diverged_penalty;
  return v;
}

std::vector<double> ProblemFitness::operator()(const std::vector<Decision>& batch) {
  std::vector<sim::ControllerConfig> controllers;
  controllers.reserve(batch.size());
  for (const Decision& x : batch) controllers.push_back(problem_.controller_for(x));
  const std::vector<CandidateOutcome> out = problem_.evaluate(controllers, evaluator_);
  simulations_ += static_cast<std::int64_t>(controllers.size() * problem_.scenarios());
  std::vector<double> J(batch.size());
  for (std::size_t i = 0; i < batch.size(); ++i) J[i] = out[i].evaluation.fitness;
  return J;
}

}  // namespace ftc::tune
