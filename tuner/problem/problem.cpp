#include "ftc/tune/problem/problem.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <cstring>
#include <limits>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>

#include "ftc/runtime/json_reader.hpp"
#include "ftc/sim/elementary.hpp"
#include "ftc/tune/job/ensemble.hpp"
#include "ftc/tune/optimizers/pareto_bat.hpp"

namespace ftc::tune {
namespace {

bool same_window(const sim::Window& a, const sim::Window& b) {
  return a.t0 == b.t0 && a.t1 == b.t1;
}

// The simulation options of a scenario: the objective window, the fault segments (before the
// first onset, between onsets, after the last) and each goal's own window as extra windows, and
// the job's metric settings (its metrics block, or a goal's threshold and tail).
sim::SimulationOptions options_of(const Job& job, const sim::Scenario& s) {
  sim::SimulationOptions o;
  o.window = job.objective.window_of(s);
  if (job.metrics) {
    constexpr double nan = std::numeric_limits<double>::quiet_NaN();
    o.metrics.settling_threshold = job.metrics->settling_threshold.value_or(nan);
    o.metrics.steady_state_tail = job.metrics->steady_state_tail.value_or(nan);
  }
  for (const GoalConfig& g : job.goals) {  // validate() made sure no two disagree
    if (g.threshold) o.metrics.settling_threshold = *g.threshold;
    if (g.tail) o.metrics.steady_state_tail = *g.tail;
  }
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
  // Each goal's window, after the segments, unless it is one of them.
  for (const GoalConfig& g : job.goals) {
    if (!g.windowed()) continue;
    const sim::Window w = g.measure().window_of(s);
    if (same_window(w, o.window) ||
        std::any_of(o.extra_windows.begin(), o.extra_windows.end(),
                    [&](const sim::Window& x) { return same_window(x, w); }))
      continue;
    o.extra_windows.push_back(w);
  }
  return o;
}

std::vector<sim::SimulationOptions> options_of(const Job& job,
                                               const std::vector<sim::Scenario>& scenarios) {
  std::vector<sim::SimulationOptions> o;
  o.reserve(scenarios.size());
  for (const sim::Scenario& s : scenarios) o.push_back(options_of(job, s));
  return o;
}

bool has_limits(const Job& job) {
  return std::any_of(job.goals.begin(), job.goals.end(),
                     [](const GoalConfig& g) { return g.at_most.has_value(); });
}

// A goal's value on a scenario's metrics (TuningProblem::goal_value), where the metrics record
// keeps its field: in the goal's window; once per run (+inf for a diverged run); or once per
// fault onset, the onsets combined as the field's values over scenarios are (+inf for a diverged
// run).
double goal_value_on(const GoalConfig& g, const sim::Metrics& m, const sim::Scenario& s) {
  constexpr double inf = std::numeric_limits<double>::infinity();
  const sim::MetricField& f = *g.metric;
  switch (f.scope) {
    case sim::MetricScope::run:
      return m.diverged ? inf : m.*f.per_run;
    case sim::MetricScope::fault:
      return m.diverged ? inf : sim::over_scenarios(f, m.*f.per_fault);
    case sim::MetricScope::window:
      break;
  }
  const sim::Window w = g.measure().window_of(s);
  if (same_window(w, m.window)) return m.errors.*f.in_window;
  for (std::size_t k = 0; k < m.extra_windows.size(); ++k)
    if (same_window(w, m.extra_windows[k])) return m.extra[k].*f.in_window;
  throw std::logic_error("a goal's window was not simulated");
}

}  // namespace

// Per scenario index, what a candidate's score needs: the job's metric, whether it diverged,
// each goal's value (counted scenarios of a job with goals), and the metrics of the first
// held.size() scenarios when they are kept.
struct TuningProblem::Tally {
  std::vector<sim::Metrics> held;
  std::vector<double> values;
  std::vector<unsigned char> diverged;
  std::vector<std::vector<double>> goals;
  std::string error;  // the first task error to come in
};

double fitness_of(double objective) {
  if (!std::isfinite(objective) || objective < 0) return 0.0;
  if (objective == 0.0) return std::numeric_limits<double>::infinity();
  return 1.0 / objective;
}

double aggregate_lower_bound(const ObjectiveConfig& objective, std::vector<double> values,
                             const std::vector<bool>& known) {
  for (std::size_t i = 0; i < values.size(); ++i)
    if (i >= known.size() || !known[i]) values[i] = 0.0;
  return objective.aggregate_of(std::move(values));
}

bool goal_has_lower_bound(const GoalConfig& goal) { return goal.metric->partial_lower_bound; }

double fitness_upper_bound(double objective, double violation) {
  if (!(violation > 0)) return fitness_of(objective);
  if (!(violation <= std::numeric_limits<double>::max())) return -1.0;  // exact: V' = +inf too
  // 1 - 2^-50: rounding V/(1 + V) (twice) moves it by under 2^-52 relative either way, the
  // product below by under 2^-53, so the result stays above -V'/(1 + V') for every V' >= V,
  // although the rounded ratio itself does not always grow with V (it is 1 for V = 2^53,
  // 1 - 2^-52 for V = 2^53 + 2). A subnormal ratio comes from V < 2^-53, where 1 + V rounds to
  // 1 and V/1 is exact.
  return constrained_fitness(0.0, violation) * (1.0 - 0x1p-50);
}

std::vector<std::size_t> hardest_first(std::span<const double> reference,
                                       const std::vector<bool>& counted) {
  std::vector<std::size_t> order(counted.size());
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
  if (reference.size() != counted.size()) return order;
  const auto key = [&](std::size_t i) {
    const double v = reference[i];
    return std::isnan(v) ? std::numeric_limits<double>::infinity() : v;
  };
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    if (counted[a] != counted[b]) return static_cast<bool>(counted[a]);
    if (!counted[a]) return false;  // index order (stable)
    return key(a) > key(b);
  });
  return order;
}

std::size_t capping_block(std::size_t scenarios, std::size_t running) {
  const std::size_t wide =
      std::max(kCapBlock, (kCapRoundTasks + running - 1) / std::max<std::size_t>(1, running));
  return std::max<std::size_t>(1, std::min(wide, (scenarios + 3) / 4));
}

TuningProblem::TuningProblem(Job job) : TuningProblem(job, job.scenarios, job.scenarios.size()) {
  if (!job_->ensemble) return;
  // The members, one at a time: validated and classified here, generated again when simulated.
  members_ = static_cast<std::size_t>(job_->ensemble->count);
  member_seed_ = job_->ensemble->seed;
  const sim::AnyPlant& plant = set_->plant();
  const bool include = job_->ensemble->unrecoverable == Unrecoverable::include;
  recoverable_.reserve(scenarios());
  counted_.reserve(scenarios());
  for (std::size_t i = set_->size(); i < scenarios(); ++i) {
    const sim::Scenario sc = member(i);
    throw_if_errors("scenario " + sc.name, sc.validate("", plant.axes(), plant.actuators()));
    recoverable_.push_back(plant.recoverable(sc));
    counted_.push_back(recoverable_.back() || include);
  }
}

sim::Scenario TuningProblem::member(std::size_t i) const {
  const std::size_t k = i - set_->size();
  sim::Scenario s = ensemble_member(*job_, member_seed_, static_cast<std::int64_t>(k));
  // Every member has the base's initial-state size: member k's draws of a probe start after
  // the held scenarios' and those of the k members before it.
  for (const Perturbation& p : perturbations_) {
    SplitMix64 r = SplitMix64::member(p.seed, p.k);
    r.skip(p.held_draws + static_cast<std::uint64_t>(k) * s.initial_state.size());
    for (double& x : s.initial_state) x *= 1.0 + p.eps * (2.0 * r.uniform() - 1.0);
  }
  if (s.sensors) s.sensors->stream_seed += sensor_shift_;
  return s;
}

sim::Scenario TuningProblem::scenario(std::size_t i) const {
  if (i < set_->size()) return set_->scenario(i);
  if (i < scenarios()) return member(i);
  throw std::out_of_range("scenario " + std::to_string(i) + " of " + std::to_string(scenarios()));
}

TuningProblem::TuningProblem(Job job, std::vector<sim::Scenario> scenarios, std::size_t listed)
    : job_(std::make_shared<const Job>(std::move(job))), listed_(listed) {
  throw_if_errors("job " + job_->name, job_->validate());
  std::vector<sim::SimulationOptions> options = options_of(*job_, scenarios);
  set_ =
      std::make_shared<const SimulationSet>(job_->plant, std::move(scenarios), std::move(options));
  const sim::AnyPlant& plant = set_->plant();
  const bool include = job_->ensemble && job_->ensemble->unrecoverable == Unrecoverable::include;
  for (std::size_t i = 0; i < set_->size(); ++i) {
    const sim::Scenario& sc = set_->scenario(i);
    throw_if_errors("scenario " + sc.name, sc.validate("", plant.axes(), plant.actuators()));
    recoverable_.push_back(plant.recoverable(sc));
    counted_.push_back(recoverable_.back() || include);
  }
  if (!job_->tuning) return;
  for (const ParameterBounds& b : job_->tuning->parameters) {
    const sim::ControllerField* f = sim::find_controller_field(b.name);
    space_.names.push_back(b.name);
    const bool log = b.scale == Scale::log;
    space_.lower.push_back(log ? sim::math::log(b.lower) : b.lower);
    space_.upper.push_back(log ? sim::math::log(b.upper) : b.upper);
    scales_.push_back(b.scale);
    fields_.push_back(f->member);  // validate() made sure the field exists and is tunable
  }
}

int TuningProblem::unrecoverable() const {
  return static_cast<int>(std::count(recoverable_.begin(), recoverable_.end(), false));
}

int TuningProblem::left_out() const {
  return static_cast<int>(std::count(counted_.begin(), counted_.end(), false));
}

Decision TuningProblem::to_parameters(std::span<const double> y) const {
  Decision x(y.begin(), y.end());
  for (std::size_t j = 0; j < x.size() && j < scales_.size(); ++j)
    if (scales_[j] == Scale::log) {
      const ParameterBounds& b = job_->tuning->parameters[j];
      // exp(ln b) may miss b by an ulp either way: a search at its bound gives the bound itself.
      x[j] = y[j] >= space_.upper[j]   ? b.upper
             : y[j] <= space_.lower[j] ? b.lower
                                       : std::clamp(sim::math::exp(y[j]), b.lower, b.upper);
    }
  return x;
}

sim::ControllerConfig TuningProblem::controller_for(std::span<const double> y) const {
  return controller_with(to_parameters(y));
}

sim::ControllerConfig TuningProblem::controller_with(std::span<const double> x) const {
  sim::ControllerConfig c = job_->controller;
  for (std::size_t j = 0; j < fields_.size(); ++j) c.*fields_[j] = x[j];
  return c;
}

sim::SimulationOptions TuningProblem::simulation_options(std::size_t scenario,
                                                         std::int64_t record_every) const {
  sim::SimulationOptions o = scenario < set_->size()
                                 ? set_->options(scenario)
                                 : options_of(*job_, this->scenario(scenario));  // or throws
  o.record_every = record_every;
  return o;
}

sim::SimulationResult TuningProblem::simulate(const sim::ControllerConfig& controller,
                                              std::size_t scenario,
                                              std::int64_t record_every) const {
  const sim::SimulationOptions options = simulation_options(scenario, record_every);
  return plant().simulate(controller, this->scenario(scenario), options);
}

TuningProblem::Tally TuningProblem::new_tally(std::size_t keep, std::size_t n) const {
  Tally t;
  t.held.resize(keep);
  t.values.assign(n, 0.0);
  t.diverged.assign(n, 0);
  t.goals.assign(job_->goals.size(),
                 std::vector<double>(n, std::numeric_limits<double>::quiet_NaN()));
  return t;
}

void TuningProblem::take(Tally& t, std::size_t s, TaskResult&& r,
                         const sim::Scenario* scenario) const {
  const sim::Metrics& m = r.metrics;
  t.values[s] = job_->objective.value(m);  // +inf if diverged
  t.diverged[s] = m.diverged ? 1 : 0;
  // A task that failed holds no windows to read; its candidate meets no goal anyway.
  if (r.error.empty() && counted_[s])
    for (std::size_t g = 0; g < job_->goals.size(); ++g)
      t.goals[g][s] = goal_value_on(job_->goals[g], m, *scenario);
  if (t.error.empty() && !r.error.empty()) t.error = std::move(r.error);
  if (s < t.held.size()) t.held[s] = std::move(r.metrics);
}

Evaluation TuningProblem::finish(Tally&& t) const {
  const bool failed = !t.error.empty();
  Evaluation e;
  e.scenarios = std::move(t.held);
  e.simulated = t.values.size();
  std::vector<double> values;
  values.reserve(t.values.size());
  for (std::size_t i = 0; i < t.values.size(); ++i) {
    e.diverged = e.diverged || t.diverged[i];
    e.diverged_count += t.diverged[i] ? 1 : 0;
    if (!counted_[i]) continue;
    e.diverged_counted += t.diverged[i] ? 1 : 0;
    values.push_back(t.values[i]);
  }
  e.objective = job_->objective.aggregate_of(std::move(values));
  e.fitness = fitness_of(e.objective);
  for (std::size_t g = 0; g < job_->goals.size(); ++g) {
    const GoalConfig& goal = job_->goals[g];
    // A candidate that could not run meets no goal (its records hold no windows to read).
    if (failed) {
      e.goals.push_back(std::numeric_limits<double>::infinity());
      e.violation += goal.violation(e.goals.back());
      continue;
    }
    std::vector<double> v;
    for (std::size_t i = 0; i < t.values.size(); ++i)
      if (counted_[i]) v.push_back(t.goals[g][i]);
    const double value = aggregate_goal(goal, std::move(v));
    e.goals.push_back(value);
    e.violation += goal.violation(value);
  }
  e.fitness = constrained_fitness(e.fitness, e.violation);
  e.values = std::move(t.values);
  return e;
}

Evaluation TuningProblem::score(std::vector<sim::Metrics> per_scenario) const {
  const std::size_t n = per_scenario.size();
  Tally t = new_tally(n, n);
  for (std::size_t i = 0; i < n; ++i) {
    std::optional<sim::Scenario> sc;  // for the goals' windows
    if (!job_->goals.empty() && counted_[i]) sc = scenario(i);
    take(t, i, TaskResult{std::move(per_scenario[i]), {}, {}, {}}, sc ? &*sc : nullptr);
  }
  return finish(std::move(t));
}

double TuningProblem::goal_value(const GoalConfig& g, const sim::Metrics& m,
                                 std::size_t scenario) const {
  if (scenario < set_->size()) return goal_value_on(g, m, set_->scenario(scenario));
  return goal_value_on(g, m, this->scenario(scenario));
}

TuningProblem::Block TuningProblem::block_set(std::vector<SimulationTask> tasks) const {
  const std::size_t held = set_->size();
  if (std::all_of(tasks.begin(), tasks.end(),
                  [&](const SimulationTask& t) { return t.scenario < held; }))
    return {set_, std::move(tasks)};
  std::vector<std::size_t> ids;
  ids.reserve(tasks.size());
  for (const SimulationTask& t : tasks) ids.push_back(t.scenario);
  std::sort(ids.begin(), ids.end());
  ids.erase(std::unique(ids.begin(), ids.end()), ids.end());
  std::vector<sim::Scenario> scenarios;
  std::vector<sim::SimulationOptions> options;
  scenarios.reserve(ids.size());
  options.reserve(ids.size());
  for (std::size_t i : ids) {
    if (i < held) {
      scenarios.push_back(set_->scenario(i));
      options.push_back(set_->options(i));
    } else {
      scenarios.push_back(member(i));
      options.push_back(options_of(*job_, scenarios.back()));
    }
  }
  for (SimulationTask& t : tasks)
    t.scenario = static_cast<std::size_t>(std::lower_bound(ids.begin(), ids.end(), t.scenario) -
                                          ids.begin());
  return {std::make_shared<const SimulationSet>(
              set_->with_scenarios(std::move(scenarios), std::move(options))),
          std::move(tasks)};
}

double aggregate_goal(const GoalConfig& goal, std::vector<double> values) {
  // A scenario where the metric is undefined (NaN) is left out; undefined on every counted
  // scenario (a settling time without faults): NaN, which no limit accepts, rather than the
  // aggregate of nothing.
  std::erase_if(values, [](double x) { return std::isnan(x); });
  return values.empty() ? std::numeric_limits<double>::quiet_NaN()
                        : goal.measure().aggregate_of(std::move(values));
}

Summary summarize_values(const ObjectiveConfig& objective, std::vector<double> v) {
  Summary s;
  s.counted = static_cast<int>(v.size());
  s.objective = objective.aggregate_of(v);
  if (v.empty()) return s;
  ObjectiveConfig o = objective;
  const auto at = [&](Aggregate a, double q) {
    o.aggregate = a;
    o.q = q;
    return o.aggregate_of(v);
  };
  s.mean = at(Aggregate::mean, 0.9);
  s.median = at(Aggregate::quantile, 0.5);
  s.p90 = at(Aggregate::quantile, 0.9);
  s.p99 = at(Aggregate::quantile, 0.99);
  s.max = at(Aggregate::max, 0.9);
  o.alpha = objective.aggregate == Aggregate::cvar ? objective.alpha : 0.9;
  s.cvar = at(Aggregate::cvar, 0.9);
  return s;
}

Summary TuningProblem::summarize(const Evaluation& e) const {
  std::vector<double> v;
  for (std::size_t i = 0; i < e.values.size(); ++i)
    if (counted_[i]) v.push_back(e.values[i]);
  Summary s = summarize_values(job_->objective, std::move(v));
  s.scenarios = static_cast<int>(e.values.size());
  s.unrecoverable = unrecoverable();
  // Like the aggregates, the count follows the unrecoverable policy.
  s.diverged = e.diverged_counted;
  s.objective = e.objective;
  return s;
}

TuningProblem TuningProblem::perturbed(std::uint64_t seed, std::uint64_t k, double eps) const {
  TuningProblem p = *this;
  std::vector<sim::Scenario> scenarios;
  std::vector<sim::SimulationOptions> options;
  scenarios.reserve(set_->size());
  options.reserve(set_->size());
  SplitMix64 r = SplitMix64::member(seed, k);
  std::uint64_t draws = 0;
  for (std::size_t i = 0; i < set_->size(); ++i) {
    scenarios.push_back(set_->scenario(i));
    options.push_back(set_->options(i));  // the initial state moves no window
    for (double& x : scenarios.back().initial_state) {
      x *= 1.0 + eps * (2.0 * r.uniform() - 1.0);
      ++draws;
    }
  }
  p.set_ = std::make_shared<const SimulationSet>(
      set_->with_scenarios(std::move(scenarios), std::move(options)));
  p.perturbations_.push_back({seed, k, eps, draws});  // the members', as they are generated
  return p;
}

bool TuningProblem::has_sensors() const {
  // The members copy their base's sensors (a listed scenario) or draw them: generating every
  // member to look would cost a pass over the ensemble.
  if (members_ > 0 && job_->ensemble->sensors) return true;
  for (std::size_t i = 0; i < set_->size(); ++i) {
    if (set_->scenario(i).active_sensors()) return true;
  }
  return false;
}

TuningProblem TuningProblem::sensor_reseeded(std::uint64_t shift) const {
  TuningProblem p = *this;
  std::vector<sim::Scenario> scenarios;
  std::vector<sim::SimulationOptions> options;
  scenarios.reserve(set_->size());
  options.reserve(set_->size());
  for (std::size_t i = 0; i < set_->size(); ++i) {
    scenarios.push_back(set_->scenario(i));
    options.push_back(set_->options(i));
    if (scenarios.back().sensors) scenarios.back().sensors->stream_seed += shift;
  }
  p.set_ = std::make_shared<const SimulationSet>(
      set_->with_scenarios(std::move(scenarios), std::move(options)));
  p.sensor_shift_ += shift;
  return p;
}

std::vector<CandidateOutcome> TuningProblem::evaluate(
    std::span<const sim::ControllerConfig> controllers, BatchEvaluator& evaluator,
    std::int64_t record_every, bool keep_metrics) const {
  const std::size_t n = controllers.size(), S = scenarios();
  std::vector<CandidateOutcome> out(n);
  std::vector<Tally> tally;
  tally.reserve(n);
  for (std::size_t i = 0; i < n; ++i)
    tally.push_back(new_tally(keep_metrics ? set_->size() : 0, S));
  // Block by block of scenarios, in order (each candidate's results come in scenario order):
  // the block's members are generated for it and dropped with its results.
  const std::size_t per_block =
      std::max(kMinBlockScenarios, kBlockTasks / std::max<std::size_t>(1, n));
  std::vector<SimulationTask> t;
  for (std::size_t begin = 0; begin < S; begin += per_block) {
    const std::size_t end = std::min(S, begin + per_block);
    t.clear();
    for (std::size_t c = 0; c < n; ++c)
      for (std::size_t s = begin; s < end; ++s)
        t.push_back({c, s, record_every > 0 && s < listed_scenarios()});
    const Block b = block_set(t);
    std::vector<TaskResult> results = evaluator.run({*b.set, controllers, b.tasks, record_every});
    for (std::size_t k = 0; k < t.size(); ++k) {
      const std::size_t c = t[k].candidate;
      if (t[k].record) {
        out[c].trajectories.push_back(std::move(results[k].trajectory));
        out[c].model_invalid.push_back(results[k].model_invalid);
      }
      take(tally[c], t[k].scenario, std::move(results[k]), &b.set->scenario(b.tasks[k].scenario));
    }
  }
  for (std::size_t i = 0; i < n; ++i) {
    out[i].error = tally[i].error;
    out[i].evaluation = finish(std::move(tally[i]));
    if (!out[i].error.empty()) {
      out[i].evaluation.objective = std::numeric_limits<double>::infinity();
      // Below every candidate that ran: 0, or the worst infeasible one's -1 under limits.
      out[i].evaluation.fitness = has_limits(*job_) ? -1.0 : 0.0;
    }
  }
  return out;
}

std::vector<CandidateOutcome> TuningProblem::evaluate_capped(
    std::span<const sim::ControllerConfig> controllers, std::span<const double> caps,
    std::span<const std::size_t> order, BatchEvaluator& evaluator) const {
  if (caps.size() != controllers.size())
    throw std::invalid_argument("evaluate_capped: a cap per candidate, an order of every scenario");
  std::vector<bool> may_stop(caps.size());
  for (std::size_t c = 0; c < caps.size(); ++c) may_stop[c] = caps[c] > kNoCap;
  return evaluate_capped(
      controllers, may_stop,
      [&](std::size_t c, const PartialBounds& b) { return b.fitness < caps[c]; }, order, evaluator);
}

std::vector<CandidateOutcome> TuningProblem::evaluate_capped(
    std::span<const sim::ControllerConfig> controllers, const std::vector<bool>& may_stop,
    const StopRule& stop, std::span<const std::size_t> order, BatchEvaluator& evaluator) const {
  const std::size_t n = controllers.size(), S = scenarios();
  if (may_stop.size() != n || order.size() != S)
    throw std::invalid_argument(
        "evaluate_capped: a rule per candidate, an order of every scenario");
  std::vector<Tally> tally;  // by scenario: each candidate's come in its order
  tally.reserve(n);
  for (std::size_t c = 0; c < n; ++c) tally.push_back(new_tally(0, S));
  std::vector<std::vector<bool>> known(n, std::vector<bool>(S, false));
  std::vector<std::size_t> done(n, 0);  // how many of `order` ran
  const auto error = [&](std::size_t c) -> const std::string& { return tally[c].error; };
  std::vector<bool> running(n, true), capped(n, false);
  std::vector<double> bound(n, 0.0), upper(n, 0.0), violation_bound(n, 0.0);
  std::vector<std::vector<double>> goal_bound(n);
  std::vector<SimulationTask> tasks;
  for (;;) {
    std::vector<std::size_t> live;
    for (std::size_t c = 0; c < n; ++c)
      if (running[c]) live.push_back(c);
    if (live.empty()) break;
    const std::size_t block = capping_block(S, live.size());
    tasks.clear();
    for (std::size_t c : live)
      for (std::size_t k = done[c]; k < std::min(S, done[c] + block); ++k)
        tasks.push_back({c, order[k], false});
    const Block b = block_set(tasks);
    std::vector<TaskResult> results = evaluator.run({*b.set, controllers, b.tasks, 0});
    for (std::size_t t = 0; t < tasks.size(); ++t) {
      const std::size_t c = tasks[t].candidate, s = tasks[t].scenario;
      take(tally[c], s, std::move(results[t]), &b.set->scenario(b.tasks[t].scenario));
      known[c][s] = true;
    }
    for (std::size_t c : live) {
      done[c] = std::min(S, done[c] + block);
      if (done[c] == S) {
        running[c] = false;
        continue;
      }
      if (!may_stop[c]) continue;
      // The counted values in scenario order, as score() aggregates them; a task that failed
      // makes the candidate's objective +inf.
      std::vector<double> values;
      std::vector<bool> have;
      for (std::size_t s = 0; s < S; ++s)
        if (counted_[s]) {
          values.push_back(known[c][s] ? tally[c].values[s] : 0.0);
          have.push_back(known[c][s]);
        }
      bound[c] = error(c).empty() ? aggregate_lower_bound(job_->objective, std::move(values), have)
                                  : std::numeric_limits<double>::infinity();
      // A job with goals: each goal's lower bound the same way, and the violation they give.
      goal_bound[c].clear();
      violation_bound[c] = 0.0;
      for (std::size_t gi = 0; gi < job_->goals.size(); ++gi) {
        const GoalConfig& g = job_->goals[gi];
        double lb = std::numeric_limits<double>::quiet_NaN();  // no bound: counts 0 below
        if (!error(c).empty()) {
          lb = std::numeric_limits<double>::infinity();  // as score() has a failed candidate
        } else if (goal_has_lower_bound(g)) {
          std::vector<double> v;
          for (std::size_t s = 0; s < S; ++s)
            if (counted_[s]) v.push_back(known[c][s] ? tally[c].goals[gi][s] : 0.0);
          lb = aggregate_lower_bound(g.measure(), std::move(v), have);
        }
        goal_bound[c].push_back(lb);
        if (!std::isnan(lb)) violation_bound[c] += g.violation(lb);
      }
      // A failed candidate's fitness is known: evaluate()'s.
      const double most = !error(c).empty() && has_limits(*job_)
                              ? -1.0
                              : fitness_upper_bound(bound[c], violation_bound[c]);
      if (stop(c, {bound[c], most, violation_bound[c], goal_bound[c]})) {
        capped[c] = true;
        running[c] = false;
        upper[c] = most;
      }
    }
  }
  std::vector<CandidateOutcome> out(n);
  for (std::size_t c = 0; c < n; ++c) {
    if (capped[c]) {
      Evaluation& e = out[c].evaluation;
      e.capped = true;
      e.simulated = done[c];
      e.objective = bound[c];
      e.fitness = upper[c];
      e.goals = std::move(goal_bound[c]);
      e.violation = violation_bound[c];
      for (std::size_t s = 0; s < S; ++s)
        if (known[c][s] && tally[c].diverged[s]) ++e.diverged_count;
      e.diverged = e.diverged_count > 0;
      out[c].error = error(c);
      continue;
    }
    out[c].error = error(c);
    out[c].evaluation = finish(std::move(tally[c]));
    if (!out[c].error.empty()) {  // as evaluate() does
      out[c].evaluation.objective = std::numeric_limits<double>::infinity();
      out[c].evaluation.fitness = has_limits(*job_) ? -1.0 : 0.0;
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
  for (std::size_t j = 0; j < x.size(); ++j) {
    const ParameterBounds& b = job_->tuning->parameters[j];  // natural units, like x
    if (!(x[j] >= b.lower && x[j] <= b.upper))
      errs.push_back({std::string("/").append(std::to_string(j)),
                      b.name + " = " + json_io::number_text(x[j], 17) + " is outside its bounds [" +
                          json_io::number_text(b.lower) + ", " + json_io::number_text(b.upper) +
                          "]"});
  }
  throw_if_errors("objective", std::move(errs));
  SerialEvaluator serial;
  const sim::ControllerConfig c = controller_with(x);
  const CandidateOutcome o = evaluate(std::span<const sim::ControllerConfig>(&c, 1), serial)[0];
  if (!o.error.empty()) throw InputError("objective", "", o.error);
  // The job's aggregate: +inf when a counted scenario diverged into it, finite when the only
  // diverged runs are left out (unrecoverable) or below a quantile.
  const double v = o.evaluation.objective;
  if (!std::isfinite(v) && options.diverged_penalty) return *options.diverged_penalty;
  return v;
}

std::size_t front_objectives(const Job& job) {
  const auto soft = static_cast<std::size_t>(std::count_if(
      job.goals.begin(), job.goals.end(), [](const GoalConfig& g) { return g.soft(); }));
  return soft >= 2 ? soft : 0;
}

ObjectiveVector objective_vector(const Job& job, const Evaluation& e) {
  ObjectiveVector o;
  for (std::size_t k = 0; k < job.goals.size() && k < e.goals.size(); ++k)
    if (job.goals[k].soft())  // an undefined goal (NaN) is no better than any value
      o.values.push_back(std::isnan(e.goals[k]) ? std::numeric_limits<double>::infinity()
                                                : e.goals[k]);
  o.violation = e.violation;
  return o;
}

std::unique_ptr<Optimizer> make_optimizer(const TuningProblem& problem,
                                          const AlgorithmSettings& algorithm, std::uint64_t seed) {
  if (const std::size_t n = front_objectives(problem.job())) {
    if (!algorithm.searches_front())  // Job::validate refuses this; a program may not ask it
      throw InputError("job " + problem.job().name, "/tuning/algorithm/type",
                       "algorithm " + algorithm.type() + " does not search for a Pareto front");
    return algorithm.make_front(seed, problem.space(), n);
  }
  return algorithm.make(seed, problem.space());
}

std::size_t ProblemFitness::objectives() const { return front_objectives(problem_.job()); }

std::vector<ObjectiveVector> ProblemFitness::objective_vectors(const std::vector<Decision>& batch) {
  if (objectives() < 2) return BatchFitness::objective_vectors(batch);  // throws
  std::vector<ObjectiveVector> out;
  run(batch, &out);
  return out;
}

std::vector<double> ProblemFitness::operator()(const std::vector<Decision>& batch) {
  return run(batch, nullptr);
}

namespace {

// FNV-1a over the bits of the values: equal bits, equal hash.
std::uint64_t bits_hash(const Decision& x) {
  std::uint64_t h = 1469598103934665603ull;
  for (double v : x) {
    std::uint64_t b = 0;
    std::memcpy(&b, &v, sizeof b);
    for (int k = 0; k < 8; ++k) {
      h ^= (b >> (8 * k)) & 0xffu;
      h *= 1099511628211ull;
    }
  }
  return h;
}

bool same_bits(const Decision& a, const Decision& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(double)) == 0;
}

}  // namespace

ProblemFitness::Served ProblemFitness::serve(const std::vector<Decision>& batch) const {
  Served s;
  const std::size_t n = batch.size();
  s.parameters.reserve(n);
  s.source.assign(n, std::nullopt);
  s.first = trials_.size();
  // The batch's own candidates by hash (first of equal parameters), to find duplicates in it.
  std::unordered_multimap<std::uint64_t, std::size_t> in_batch;
  for (std::size_t i = 0; i < n; ++i) {
    s.parameters.push_back(problem_.to_parameters(batch[i]));
    const Decision& x = s.parameters.back();
    if (!cache_) {
      s.simulate.push_back(i);
      continue;
    }
    const std::uint64_t h = bits_hash(x);
    for (auto [it, last] = by_parameters_.equal_range(h); it != last && !s.source[i]; ++it)
      if (same_bits(trials_[it->second].parameters, x)) s.source[i] = it->second;
    for (auto [it, last] = in_batch.equal_range(h); it != last && !s.source[i]; ++it)
      if (same_bits(s.parameters[it->second], x)) s.source[i] = s.first + it->second;
    if (s.source[i]) continue;
    in_batch.emplace(h, i);
    s.simulate.push_back(i);
  }
  return s;
}

std::vector<double> ProblemFitness::run(const std::vector<Decision>& batch,
                                        std::vector<ObjectiveVector>* vectors) {
  const Served s = serve(batch);
  std::vector<sim::ControllerConfig> controllers;
  controllers.reserve(s.simulate.size());
  for (std::size_t i : s.simulate) controllers.push_back(problem_.controller_with(s.parameters[i]));
  return record(s, problem_.evaluate(controllers, evaluator_, 0, false), vectors);
}

std::vector<double> ProblemFitness::evaluate_capped(const std::vector<Decision>& batch,
                                                    const std::vector<double>& caps) {
  const bool any = std::any_of(caps.begin(), caps.end(), [](double c) { return c > kNoCap; });
  if (!capping_ || !any || problem_.scenarios() < 2 || caps.size() != batch.size())
    return (*this)(batch);
  return run_capped(batch, &caps, nullptr, nullptr);
}

std::vector<ObjectiveVector> ProblemFitness::objective_vectors_capped(
    const std::vector<Decision>& batch, const std::vector<FrontCap>& caps) {
  if (!capping_ || objectives() < 2 || problem_.scenarios() < 2 || caps.size() != batch.size())
    return objective_vectors(batch);
  std::vector<ObjectiveVector> out;
  run_capped(batch, nullptr, &caps, &out);
  return out;
}

namespace {

// A front candidate's objective vector of lower bounds (FrontCap::stops reads it).
ObjectiveVector lower_objective_vector(const Job& job, const TuningProblem::PartialBounds& b) {
  ObjectiveVector o;
  for (std::size_t k = 0; k < job.goals.size() && k < b.goals.size(); ++k)
    if (job.goals[k].soft())  // a goal without a bound is at least -inf
      o.values.push_back(std::isnan(b.goals[k]) ? -std::numeric_limits<double>::infinity()
                                                : b.goals[k]);
  o.violation = b.violation;
  return o;
}

}  // namespace

std::vector<std::size_t> ProblemFitness::capping_order() {
  // After a resume the incumbent's values are not in the checkpoint: simulate it again (the
  // same bits as when it was found), so that the order is the uninterrupted run's.
  if (incumbent_.empty()) {
    const Trial* best = nullptr;
    for (const Trial& t : trials_)
      if (t.accepted && !t.capped) best = &t;
    if (best) {
      const sim::ControllerConfig c = problem_.controller_with(best->parameters);
      const CandidateOutcome o =
          problem_.evaluate(std::span<const sim::ControllerConfig>(&c, 1), evaluator_, 0, false)[0];
      simulations_ += static_cast<std::int64_t>(problem_.scenarios());
      incumbent_ = o.evaluation.values;
    }
  }
  std::vector<bool> counted(problem_.scenarios());
  for (std::size_t s = 0; s < counted.size(); ++s) counted[s] = problem_.counted(s);
  return hardest_first(incumbent_, counted);
}

std::vector<double> ProblemFitness::run_capped(const std::vector<Decision>& batch,
                                               const std::vector<double>* caps,
                                               const std::vector<FrontCap>* front_caps,
                                               std::vector<ObjectiveVector>* vectors) {
  const Job& job = problem_.job();
  const bool front = objectives() >= 2;
  const std::vector<std::size_t> order = capping_order();
  const Served served = serve(batch);
  // A candidate simulated for its duplicates in the batch too stops only where each of them
  // would have: capped then, each would have been.
  std::vector<std::vector<std::size_t>> askers(batch.size());
  for (std::size_t i = 0; i < batch.size(); ++i) {
    const std::optional<std::size_t>& from = served.source[i];
    if (!from)
      askers[i].push_back(i);
    else if (*from >= served.first)  // a duplicate of candidate *from - first of this batch
      askers[*from - served.first].push_back(i);
  }
  // Random search over a front (scalar caps) keeps every trial it ran: a candidate may stop
  // only if it cannot enter the run's front, that is if its bounds are infeasible or some
  // trial on that front dominates them. The run's front is a front optimiser's archive without
  // a capacity (offer_to_front keeps it by NonDominated's rule in run/front.cpp).
  const FrontCap run_front{false, {}, front_};
  std::vector<sim::ControllerConfig> controllers;
  std::vector<bool> may_stop;
  std::vector<const std::vector<std::size_t>*> rules;
  controllers.reserve(served.simulate.size());
  for (std::size_t i : served.simulate) {
    controllers.push_back(problem_.controller_with(served.parameters[i]));
    bool may = true;
    for (std::size_t a : askers[i]) may = may && (!caps || (*caps)[a] > kNoCap);
    may_stop.push_back(may);
    rules.push_back(&askers[i]);
  }
  // A front's trial must not be one "best so far" either (trials.csv's accepted): its fitness
  // is at most that of the best trial at the batch's start, which only grows.
  const double best = best_;
  const auto stop = [&](std::size_t c, const TuningProblem::PartialBounds& b) {
    if (front && !(b.fitness <= best)) return false;
    const ObjectiveVector lower = front ? lower_objective_vector(job, b) : ObjectiveVector{};
    return std::all_of(rules[c]->begin(), rules[c]->end(), [&](std::size_t a) {
      if (caps && !(b.fitness < (*caps)[a])) return false;
      if (!front) return true;
      return (front_caps ? (*front_caps)[a] : run_front).stops(lower);
    });
  };
  return record(served, problem_.evaluate_capped(controllers, may_stop, stop, order, evaluator_),
                vectors);
}

std::vector<double> ProblemFitness::record(const Served& s, std::vector<CandidateOutcome> out,
                                           std::vector<ObjectiveVector>* vectors) {
  const std::size_t n = s.parameters.size();
  std::vector<double> J(n);
  const bool per_scenario = !problem_.job().ensemble;
  assert(s.first == trials_.size());
  std::size_t next = 0;  // into out, in s.simulate order
  for (std::size_t i = 0; i < n; ++i) {
    if (s.source[i]) {
      // A copy of an earlier trial: no simulation, never accepted (its fitness was there to
      // beat). trials_ grows below, so the source is copied before the push.
      Trial t = trials_[*s.source[i]];
      t.iteration = iteration_;
      t.index = index_++;
      t.accepted = false;
      t.cached = true;
      J[i] = t.fitness;
      if (vectors) {
        Evaluation e;
        e.goals = t.goals;
        e.violation = t.violation;
        vectors->push_back(objective_vector(problem_.job(), e));
      }
      trials_.push_back(std::move(t));
      continue;
    }
    assert(next < s.simulate.size() && s.simulate[next] == i);
    const Evaluation& e = out[next++].evaluation;
    simulations_ += static_cast<std::int64_t>(e.simulated);
    J[i] = e.fitness;
    if (vectors) vectors->push_back(objective_vector(problem_.job(), e));
    Trial t;
    t.iteration = iteration_;
    t.index = index_++;
    t.parameters = s.parameters[i];
    t.objective = e.objective;
    t.fitness = e.fitness;
    t.diverged = e.diverged_count;
    t.capped = e.capped;
    if (e.capped) t.simulated = e.simulated;
    if (per_scenario) t.scenario_objectives = e.values;
    t.goals = e.goals;
    t.violation = e.violation;
    // A capped candidate's fitness is below its cap, which is at most the best so far.
    t.accepted = !e.capped && e.fitness > best_;
    if (t.accepted) {
      best_ = e.fitness;
      incumbent_ = e.values;
    }
    trials_.push_back(std::move(t));
    if (cache_ && !trials_.back().capped) index_trial(trials_.size() - 1);
    if (!e.capped) offer_to_front(objective_vector(problem_.job(), e));
  }
  return J;
}

void ProblemFitness::offer_to_front(const ObjectiveVector& o) {
  if (objectives() < 2 || !o.feasible() ||
      !std::all_of(o.values.begin(), o.values.end(), [](double v) { return std::isfinite(v); }))
    return;
  for (const ObjectiveVector& m : *front_)
    if (m.values == o.values || pareto::dominates(m, o)) return;
  auto next = std::make_shared<std::vector<ObjectiveVector>>();
  for (const ObjectiveVector& m : *front_)
    if (!pareto::dominates(o, m)) next->push_back(m);
  next->push_back(o);
  front_ = std::move(next);
}

std::int64_t cached_trials(const std::vector<Trial>& trials) {
  return std::count_if(trials.begin(), trials.end(), [](const Trial& t) { return t.cached; });
}

void ProblemFitness::index_trial(std::size_t i) {
  by_parameters_.emplace(bits_hash(trials_[i].parameters), i);
}

void ProblemFitness::resume_trials(std::vector<Trial> before) {
  trials_ = std::move(before);
  by_parameters_.clear();
  front_ = std::make_shared<const std::vector<ObjectiveVector>>();
  for (std::size_t i = 0; i < trials_.size(); ++i) {
    const Trial& t = trials_[i];
    if (!t.capped) {
      best_ = std::max(best_, t.fitness);
      Evaluation e;
      e.goals = t.goals;
      e.violation = t.violation;
      offer_to_front(objective_vector(problem_.job(), e));
    }
    // The run that was interrupted served from its first uncapped trial of each parameter set.
    if (cache_ && !t.capped && !t.cached) index_trial(i);
  }
  incumbent_.clear();
}

}  // namespace ftc::tune
