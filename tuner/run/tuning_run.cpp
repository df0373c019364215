#include "ftc/tune/run/tuning_run.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <span>

#include "ftc/runtime/json_reader.hpp"
#include "ftc/sim/controller_config.hpp"
#include "ftc/sim/elementary.hpp"
#include "ftc/sim/metrics_record.hpp"
#include "ftc/tune/io/sha256.hpp"
#include "ftc/tune/job/ensemble.hpp"
#include "ftc/tune/run/documents.hpp"
#include "ftc/tune/run/memory_budget.hpp"

namespace ftc::tune {

std::string display_name(sim::ControllerType t) { return sim::controller_info(t).display_name; }

std::string canonical_job_sha256(const Job& job) { return sha256_hex(to_json(job).dump()); }

namespace {

// A trial as a compact row: [iteration, index, [parameters], objective, fitness, diverged,
// [objective per scenario], accepted]; a diverged objective (inf) is null. A capped trial
// (issue 27) has one more element: how many scenarios it simulated; a cached one (issue 43) has
// true at the end.
nlohmann::json trial_json(const Trial& t) {
  nlohmann::json scen = nlohmann::json::array();
  for (double v : t.scenario_objectives) scen.push_back(json_io::json_number(v));
  nlohmann::json row =
      nlohmann::json::array({t.iteration, t.index, t.parameters, json_io::json_number(t.objective),
                             t.fitness, t.diverged, scen, t.accepted});
  if (!t.goals.empty()) {  // a job with goals: [goal values], total violation
    nlohmann::json goals = nlohmann::json::array();
    // +inf (a diverged member's) as "inf", so that a resumed run tells it from NaN (null: no
    // scenario defines the metric, or a capped row's goal without a bound) as the run did.
    for (double v : t.goals)
      goals.push_back(std::isinf(v) && v > 0 ? nlohmann::json("inf") : json_io::json_number(v));
    row.push_back(std::move(goals));
    row.push_back(json_io::json_number(t.violation));
  }
  if (t.capped) row.push_back(t.simulated);
  if (t.cached) row.push_back(true);
  return row;
}

}  // namespace

// A job with n goals has rows of 10 with n goal values, one without goals rows of 8; a capped
// trial's row one more, its count of scenarios simulated, and a cached one's one more, true.
std::vector<Trial> trials_from_json(const nlohmann::json& rows, std::size_t goals) {
  const auto bad = [] {
    return InputError("checkpoint", "/trials", "is not a list of trials written by ftctune");
  };
  if (!rows.is_array()) throw bad();
  std::vector<Trial> out;
  for (const nlohmann::json& r : rows) {
    const std::size_t base = goals ? 10u : 8u;
    const bool cached = r.is_array() && r.size() > base && r.back().is_boolean() &&
                        r.back().get<bool>();
    const std::size_t size = r.is_array() ? r.size() - (cached ? 1 : 0) : 0;
    if (!r.is_array() || (size != base && size != base + 1) ||
        (cached && r[7].is_boolean() && r[7].get<bool>()) ||  // a cached trial is never accepted
        (size == base + 1 && !r[base].is_number_unsigned()) || !r[0].is_number_integer() ||
        !r[1].is_number_integer() || !r[2].is_array() || !r[4].is_number() ||
        !r[5].is_number_integer() || !r[6].is_array() || !r[7].is_boolean())
      throw bad();
    Trial t;
    t.iteration = r[0].get<int>();
    t.index = r[1].get<int>();
    for (const nlohmann::json& p : r[2]) {
      if (!p.is_number()) throw bad();
      t.parameters.push_back(p.get<double>());
    }
    t.objective = json_io::json_number_or(r[3], std::numeric_limits<double>::infinity());
    t.fitness = r[4].get<double>();
    t.diverged = r[5].get<int>();
    for (const nlohmann::json& v : r[6])
      t.scenario_objectives.push_back(
          json_io::json_number_or(v, std::numeric_limits<double>::infinity()));
    t.accepted = r[7].get<bool>();
    if (size == base + 1) {
      t.capped = true;
      t.simulated = r[base].get<std::size_t>();
    }
    t.cached = cached;
    if (goals) {
      if (!r[8].is_array() || r[8].size() != goals || !(r[9].is_number() || r[9].is_null()))
        throw bad();
      for (const nlohmann::json& v : r[8]) {
        if (v.is_string() && v.get<std::string>() == "inf") {
          t.goals.push_back(std::numeric_limits<double>::infinity());
          continue;
        }
        if (!v.is_number() && !v.is_null()) throw bad();
        // null: NaN (no scenario defines the metric, or a capped row's goal without a bound)
        t.goals.push_back(json_io::json_number_or(v, std::numeric_limits<double>::quiet_NaN()));
      }
      t.violation = json_io::json_number_or(r[9], std::numeric_limits<double>::infinity());
    }
    out.push_back(std::move(t));
  }
  return out;
}

nlohmann::json trials_json(const std::vector<Trial>& trials, std::size_t from) {
  nlohmann::json rows = nlohmann::json::array();
  for (std::size_t i = from; i < trials.size(); ++i) rows.push_back(trial_json(trials[i]));
  return rows;
}

nlohmann::json run_checkpoint(const Optimizer& optimizer, const std::vector<Trial>& trials) {
  return {{"optimizer", optimizer.state()}, {"trials", trials_json(trials)}};
}

namespace {

// What the problem scores, as the outcome records it.
void describe_problem(const TuningProblem& problem, TuningOutcome& r) {
  r.scenarios = problem.scenarios();
  r.listed_scenarios = problem.listed_scenarios();
  r.unrecoverable = problem.unrecoverable();
  r.left_out = problem.left_out();
  r.listed_recoverable.clear();
  for (std::size_t i = 0; i < problem.listed_scenarios(); ++i)
    r.listed_recoverable.push_back(problem.recoverable(i));
}

// Each controller's extremes over the noise floor's R re-evaluations (SPEC §14): its objective's
// and each goal's least and greatest value.
struct PerturbedExtremes {
  double objective_min = std::numeric_limits<double>::infinity();
  double objective_max = -std::numeric_limits<double>::infinity();
  std::vector<double> goal_min, goal_max;
};

// `controllers` on `repeats` copies of the problem, copy k made by `copy(k)`: one batch per copy,
// so the evaluator fills its lanes, threads and ranks, and each controller's results come back by
// its index, whatever else the batch holds.
template <class Copy>
std::vector<PerturbedExtremes> perturbed_extremes(
    const TuningProblem& problem, int repeats, Copy&& copy,
    std::span<const sim::ControllerConfig> controllers, BatchEvaluator& evaluator) {
  const std::size_t goals = problem.job().goals.size();
  std::vector<PerturbedExtremes> ex(controllers.size());
  for (PerturbedExtremes& e : ex) {
    e.goal_min.assign(goals, std::numeric_limits<double>::infinity());
    e.goal_max.assign(goals, -std::numeric_limits<double>::infinity());
  }
  // In groups of as many controllers as the run scores at once (the memory budget's count): each
  // controller's result depends on its own tasks only, so the grouping changes no bit.
  const std::size_t group = std::max<std::size_t>(1, controllers_at_once(problem.job()));
  for (int k = 0; k < repeats; ++k) {
    const TuningProblem p = copy(k);
    for (std::size_t from = 0; from < controllers.size(); from += group) {
      const std::size_t n = std::min(group, controllers.size() - from);
      const std::vector<CandidateOutcome> out =
          p.evaluate(controllers.subspan(from, n), evaluator, 0, false);
      for (std::size_t j = 0; j < out.size(); ++j) {
        const std::size_t i = from + j;
        const Evaluation& e = out[j].evaluation;
        ex[i].objective_min = std::min(ex[i].objective_min, e.objective);
        ex[i].objective_max = std::max(ex[i].objective_max, e.objective);
        for (std::size_t g = 0; g < goals && g < e.goals.size(); ++g) {
          ex[i].goal_min[g] = std::min(ex[i].goal_min[g], e.goals[g]);
          ex[i].goal_max[g] = std::max(ex[i].goal_max[g], e.goals[g]);
        }
      }
    }
  }
  return ex;
}

// Each controller's extremes over both sets of runs.
std::vector<PerturbedExtremes> merged(std::vector<PerturbedExtremes> a,
                                      const std::vector<PerturbedExtremes>& b) {
  for (std::size_t i = 0; i < a.size() && i < b.size(); ++i) {
    a[i].objective_min = std::min(a[i].objective_min, b[i].objective_min);
    a[i].objective_max = std::max(a[i].objective_max, b[i].objective_max);
    for (std::size_t g = 0; g < a[i].goal_min.size() && g < b[i].goal_min.size(); ++g) {
      a[i].goal_min[g] = std::min(a[i].goal_min[g], b[i].goal_min[g]);
      a[i].goal_max[g] = std::max(a[i].goal_max[g], b[i].goal_max[g]);
    }
  }
  return a;
}

// Each goal's relative spread (max - min)/|value| at a point whose goal values are `at`; none
// where the value is 0 or not finite or a re-run's value is not finite.
std::vector<std::optional<double>> goal_spreads(const PerturbedExtremes& ex,
                                                const std::vector<double>& at) {
  std::vector<std::optional<double>> spread(ex.goal_min.size());
  for (std::size_t g = 0; g < spread.size() && g < at.size(); ++g)
    if (std::isfinite(ex.goal_max[g]) && std::isfinite(ex.goal_min[g]) && at[g] != 0 &&
        std::isfinite(at[g]))
      spread[g] = (ex.goal_max[g] - ex.goal_min[g]) / std::abs(at[g]);
  return spread;
}

// The sensor seed of the first scenario with sensors (the noise floor lists the seeds it moved
// it to). Every ensemble member has the same seed, so the first member tells it (generating
// every member until one reads sensors would cost a pass over the ensemble).
std::uint64_t first_sensor_seed(const TuningProblem& problem) {
  for (std::size_t i = 0; i < problem.listed_scenarios(); ++i) {
    const sim::Scenario s = problem.scenario(i);
    if (s.active_sensors()) return s.sensors->stream_seed;
  }
  if (problem.scenarios() > problem.listed_scenarios()) {
    // Its block, exact or not: a member whose draws gave it no noise still has the seed.
    const sim::Scenario member = problem.scenario(problem.listed_scenarios());
    if (member.sensors) return member.sensors->stream_seed;
  }
  return 0;
}

// The controllers of a front's points, in its order.
std::vector<sim::ControllerConfig> front_controllers(const TuningProblem& problem,
                                                     const Front& front) {
  std::vector<sim::ControllerConfig> c;
  c.reserve(front.points.size());
  for (const FrontPoint& p : front.points) c.push_back(problem.controller_with(p.parameters));
  return c;
}

// The comparison of r's best controller with the job's own and its compare entries, and the
// noise floor of the best (tune() after a completed run, compare_best() after a stopped one).
void compare_with(const TuningProblem& problem, TuningOutcome& r, BatchEvaluator& evaluator,
                  std::int64_t max_trajectory_rows) {
  const Job& job = problem.job();

  for (std::size_t j = 0; j < problem.space().names.size(); ++j)
    r.tuned.emplace_back(problem.space().names[j], r.optimization.best[j]);

  std::vector<sim::ControllerConfig> controllers;
  for (const CompareEntry& c : job.compare) {
    r.comparison.push_back({c.label, "compare", c.controller, {}, {}});
    controllers.push_back(c.controller);
  }
  const std::string name = display_name(job.controller.type);
  r.comparison.push_back({name + " (job)", "baseline", job.controller, {}, {}});
  controllers.push_back(job.controller);
  r.comparison.push_back({"tuned " + name, "tuned", r.tuned_controller, {}, {}});
  controllers.push_back(r.tuned_controller);

  std::vector<CandidateOutcome> outcomes =
      problem.evaluate(controllers, evaluator, comparison_record_every(job, max_trajectory_rows));
  for (std::size_t i = 0; i < outcomes.size(); ++i) {
    r.comparison[i].summary = problem.summarize(outcomes[i].evaluation);
    r.comparison[i].outcome = std::move(outcomes[i]);
  }
  r.simulations += static_cast<std::int64_t>(controllers.size() * problem.scenarios());
  // The front's figures mark the comparison's controllers other than the tuned one.
  if (r.front) {
    for (const ComparedController& c : r.comparison)
      if (c.role != "tuned")
        r.front->compared.push_back(
            {c.label, c.role, c.outcome.evaluation.goals, c.outcome.evaluation.feasible()});
    mark_dominated_by_compared(*r.front);
  }
  // The noise floor: the winner (with a front, every point of it) on R copies of the problem
  // whose initial states are nudged.
  NoiseFloor nf;
  std::vector<sim::ControllerConfig> probed{r.tuned_controller};
  std::size_t tuned_at = 0;
  const bool every_point = !job.tuning || job.tuning->noise_floor == FrontNoiseFloor::every_point;
  if (r.front && !r.front->points.empty() && every_point) {
    probed = front_controllers(problem, *r.front);
    tuned_at = r.front->picked;
    probed[tuned_at] = r.tuned_controller;
  }
  // The nudged initial states (streams kNoiseFloorStream + k, relative size nf.perturbation)
  // give the rounding's share; with sensors, the other sensor seeds (each scenario's seed + 1
  // ... + repeats, SPEC §18) the noise's, and the floor is the spread over both.
  const std::vector<PerturbedExtremes> nudged = perturbed_extremes(
      problem, nf.repeats,
      [&](int k) {
        return problem.perturbed(r.seed, kNoiseFloorStream + static_cast<std::uint64_t>(k),
                                 nf.perturbation);
      },
      probed, evaluator);
  std::vector<PerturbedExtremes> ex = nudged;
  const double own = r.best().outcome.evaluation.objective;
  const auto spread = [&](const PerturbedExtremes& e) {
    return (e.objective_max - e.objective_min) / own;
  };
  if (problem.has_sensors()) {
    const std::vector<PerturbedExtremes> sensed = perturbed_extremes(
        problem, nf.repeats,
        [&](int k) { return problem.sensor_reseeded(static_cast<std::uint64_t>(k) + 1); }, probed,
        evaluator);
    const std::uint64_t first = first_sensor_seed(problem);
    for (int k = 1; k <= nf.repeats; ++k) nf.sensor_seeds.push_back(first + k);
    nf.rounding_spread = spread(nudged[tuned_at]);
    nf.sensor_spread = spread(sensed[tuned_at]);
    ex = merged(nudged, sensed);
    r.simulations += static_cast<std::int64_t>(nf.repeats) *
                     static_cast<std::int64_t>(probed.size() * problem.scenarios());
  }
  nf.objective_min = ex[tuned_at].objective_min;
  nf.objective_max = ex[tuned_at].objective_max;
  if (r.front && !r.front->points.empty()) {
    // "noise_floor": "picked": the other points' floors are unknown.
    std::vector<std::vector<std::optional<double>>> spreads;
    for (std::size_t i = 0; i < r.front->points.size(); ++i)
      spreads.push_back(
          every_point || i == r.front->picked
              ? goal_spreads(ex[every_point ? i : 0], r.front->points[i].goals)
              : std::vector<std::optional<double>>(r.front->points[i].goals.size(), std::nullopt));
    apply_noise_floor(*r.front, spreads);
  }
  r.simulations += static_cast<std::int64_t>(nf.repeats) *
                   static_cast<std::int64_t>(probed.size() * problem.scenarios());
  nf.relative_spread = spread(ex[tuned_at]);
  r.noise_floor = nf;
  // A parameter on its bound: does the objective change there by more than the noise? The tuned
  // controller with that parameter moved 1 % of its range inward says.
  std::vector<std::optional<double>> inward(r.optimization.best.size());
  for (std::size_t j = 0; j < job.tuning->parameters.size() && j < inward.size(); ++j) {
    const std::optional<double> moved =
        inward_value(job.tuning->parameters[j], r.optimization.best[j]);
    const sim::ControllerField* f = sim::find_controller_field(job.tuning->parameters[j].name);
    if (!moved || !f) continue;
    sim::ControllerConfig c = r.tuned_controller;
    c.*(f->member) = *moved;
    const double v = problem.evaluate(std::span<const sim::ControllerConfig>(&c, 1), evaluator)[0]
                         .evaluation.objective;
    r.simulations += static_cast<std::int64_t>(problem.scenarios());
    const double best = r.best().outcome.evaluation.objective;
    inward[j] = std::abs(v - best) / best;
  }
  r.warnings = bound_warnings(job, r.optimization.best, inward, nf.relative_spread);
  for (std::string& w : comparison_warnings(r)) r.warnings.push_back(std::move(w));
  if (r.front)
    if (std::string w = dominated_warning(*r.front, r.front->picked); !w.empty())
      r.warnings.push_back(std::move(w));
}

}  // namespace

TuningOutcome tune(const TuningProblem& problem, Optimizer& optimizer, AlgorithmPtr algorithm,
                   std::uint64_t seed, BatchEvaluator& evaluator, const RunOptions& options) {
  const Job& job = problem.job();
  if (!job.tuning) throw InputError("job " + job.name, "/tuning", "is required to tune");
  // With nothing counted the objective would be 0 for every candidate: any gains would "win".
  if (problem.scenarios() > 0 && problem.left_out() == static_cast<int>(problem.scenarios())) {
    if (job.ensemble)
      throw InputError("job " + job.name, "/ensemble/unrecoverable",
                       "every scenario is unrecoverable, so no gains can improve the objective; "
                       "give recoverable scenarios or set \"include\" to tune on them anyway");
    // Listed scenarios only: name them (the first one's path), and say what would help.
    std::string names;
    for (std::size_t i = 0; i < job.scenarios.size() && i < 3; ++i)
      names += (i ? ", " : "") + ("\"" + job.scenarios[i].name + "\"");
    if (job.scenarios.size() > 3) names += ", ...";
    throw InputError("job " + job.name, "/scenarios/0",
                     std::string(job.scenarios.size() == 1 ? "the only scenario (" : "every scenario (") +
                         names +
                         ") is unrecoverable: no gains can control it once its faults start, and "
                         "the objective leaves such scenarios out; give a recoverable scenario");
  }
  TuningOutcome r;
  r.job = job;
  r.job_sha256 = canonical_job_sha256(job);
  r.seed = seed;
  r.algorithm = std::move(algorithm);
  r.threads = evaluator.concurrency();
  r.threads_per_rank = evaluator.threads_per_rank();
  r.evaluator = evaluator.name();

  describe_problem(problem, r);

  // The optimiser works in search coordinates (ln x on a log scale); everything it reports
  // leaves here in parameter values.
  const auto in_values = [&](HistoryRow row) {
    row.best = problem.to_parameters(row.best);
    return row;
  };
  ProblemFitness fitness(problem, evaluator);
  fitness.set_capping(options.capping);
  fitness.set_cache(options.cache);
  // With an interrupt: the optimiser's state and the trial count after each iteration, to go
  // back to when an iteration is cut short.
  std::optional<nlohmann::json> last_state;
  std::size_t last_trials = 0;
  IterationObserver observer;
  if (options.observer || options.interrupt)
    observer = [&](const HistoryRow& h, const Optimizer& o) {
      if (options.interrupt) {
        last_state = o.state();
        last_trials = fitness.trials().size();
      }
      return !options.observer || options.observer(in_values(h), o, fitness.trials());
    };
  const nlohmann::json* optimizer_state = options.resume;
  std::string state_path;
  if (options.resume && options.resume->is_object() && options.resume->contains("optimizer")) {
    optimizer_state = &(*options.resume)["optimizer"];
    state_path = "/optimizer";
    std::vector<Trial> trials =
        trials_from_json(options.resume->value("trials", nlohmann::json()), job.goals.size());
    // One trial per evaluation so far (an evaluation count beyond the budget is restore()'s to
    // refuse, with its own path).
    const nlohmann::json& ev = optimizer_state->is_object()
                                   ? optimizer_state->value("evaluations", nlohmann::json())
                                   : nlohmann::json();
    if (ev.is_number_unsigned() &&
        ev.get<std::uint64_t>() <= static_cast<std::uint64_t>(r.algorithm->evaluations()) &&
        ev.get<std::uint64_t>() != trials.size())
      throw InputError("checkpoint", "/trials",
                       "holds " + std::to_string(trials.size()) +
                           " trials, the optimiser's state " +
                           std::to_string(ev.get<std::uint64_t>()) + " evaluations");
    fitness.resume_trials(std::move(trials));
  }
  if (options.interrupt && optimizer_state) {
    last_state = *optimizer_state;
    last_trials = fitness.trials().size();
  }
  {
    // Only the tuning is interruptible: the comparison below runs whole.
    struct Interruptible {
      BatchEvaluator& e;
      ~Interruptible() { e.set_interrupt({}); }
    } interruptible{evaluator};
    evaluator.set_interrupt(options.interrupt);
    try {
      r.optimization = run_optimizer(optimizer, fitness, observer, optimizer_state, state_path);
    } catch (const Interrupted&) {
      r.interrupted = true;
      r.simulations = fitness.simulations();
      if (!last_state) return r;  // cut short in the first iteration: nothing to keep
      optimizer.restore(*last_state);
      r.optimization = optimization_result(optimizer);
    }
  }
  r.simulations = fitness.simulations();
  r.trials = fitness.trials();
  if (r.interrupted) r.trials.resize(last_trials);  // the cut iteration's are dropped
  r.tuned_controller = problem.controller_for(r.optimization.best);
  r.optimization.best = problem.to_parameters(r.optimization.best);
  for (HistoryRow& h : r.optimization.history) h = in_values(std::move(h));
  if (front_objectives(job) >= 2 && r.optimization.completed) {
    // The front of every trial; the run's gains are its knee (a front without a feasible point:
    // the optimiser's best, the least violation).
    r.front = make_front(job, r.trials);
    if (!r.front->points.empty()) {
      const FrontPoint& knee = r.front->points[r.front->picked];
      r.optimization.best = knee.parameters;
      r.optimization.best_fitness = r.trials[knee.trial].fitness;
      r.tuned_controller = problem.controller_with(knee.parameters);
    }
    r.hypervolume = hypervolume_history(job, r.trials, r.front->reference,
                                        r.optimization.history.back().iteration);
  }
  if (!r.optimization.completed || !options.compare) return r;
  compare_with(problem, r, evaluator, options.max_trajectory_rows);
  return r;
}

std::vector<std::string> comparison_warnings(const TuningOutcome& r) {
  std::vector<std::string> out;
  if (r.comparison.empty()) return out;
  const ComparedController& tuned = r.best();
  char buf[600];
  // The tuned gains' runs of the listed scenarios that left the model's validity: their figures
  // are those of a model that no longer describes the vehicle there.
  for (std::size_t i = 0; i < r.listed_scenarios && i < tuned.outcome.model_invalid.size(); ++i)
    if (tuned.outcome.model_invalid[i].value_or(false))
      out.push_back("scenario " + r.job.scenarios[i].name + ": with the " + tuned.label +
                    " gains the pitch angle passed ±85°, near the singularity of the 3-2-1 Euler "
                    "angles, where the rigid_body model is not valid (model_invalid in "
                    "comparison.json; its metrics still count)");
  // Outcome checks of the tuned loop on each listed scenario (docs/usage.md, "Warnings"): a
  // score is no success when the loop diverged or when it ended farther from the reference than
  // it started, by more than kDriftWarningFloor. (Saturation alone is no failure: a controller
  // that keeps commanding a stuck wheel beyond its limit, as smallsat-pyramid's does, counts
  // as saturated on every sample while holding the attitude to about 2e-7 rad.)
  const double drift_floor = r.job.metrics && r.job.metrics->drift_warning
                                 ? *r.job.metrics->drift_warning
                                 : kDriftWarningFloor;
  const std::vector<sim::Metrics>& per = tuned.outcome.evaluation.scenarios;
  for (std::size_t i = 0; i < r.listed_scenarios && i < per.size(); ++i) {
    const sim::Metrics& m = per[i];
    const sim::Scenario& sc = r.job.scenarios[i];
    if (m.diverged) {
      std::snprintf(buf, sizeof buf, "scenario %s: the %s loop diverged at t = %.3f s",
                    sc.name.c_str(), tuned.label.c_str(), m.diverged_at);
      out.emplace_back(buf);
      continue;
    }
    // Never settles: with a settling threshold, a loop whose error is not below it at the end
    // of the objective window after the fault (settling_time +inf) has not recovered there.
    if (std::isinf(m.errors.settling_time) && m.errors.settling_time > 0 && r.job.metrics &&
        r.job.metrics->settling_threshold) {
      std::snprintf(buf, sizeof buf,
                    "scenario %s: the %s loop never settles after the fault: ‖e‖ is not below "
                    "the settling threshold of %.3g rad (metrics.settling_threshold) at the end "
                    "of the objective window [%.4g s, %.4g s)",
                    sc.name.c_str(), tuned.label.c_str(), *r.job.metrics->settling_threshold,
                    m.window.t0, std::min(m.window.t1, sc.duration));
      out.emplace_back(buf);
    }
    if (i >= tuned.outcome.trajectories.size() || tuned.outcome.trajectories[i].rows() == 0)
      continue;
    const sim::Trajectory& tr = tuned.outcome.trajectories[i];
    const std::size_t n = static_cast<std::size_t>(tr.axes), last = tr.rows() - 1;
    double start = 0.0, end = 0.0;
    for (std::size_t k = 0; k < n && k < sc.initial_state.size(); ++k) {
      start += sc.initial_state[k] * sc.initial_state[k];
      end += tr.x(last)[k] * tr.x(last)[k];
    }
    start = std::sqrt(start);
    end = std::sqrt(end);
    if (!(end > std::max(start, drift_floor))) continue;
    const sim::PlantKind* kind = sim::find_plant_kind(r.job.plant.model);
    const double sat = m.errors.saturation_fraction;
    char why[200] = "";
    if (sat > 0)
      std::snprintf(why, sizeof why,
                    "; its commands were at or beyond their limits on %.0f %% of the samples of "
                    "the objective window",
                    100 * sat);
    std::snprintf(buf, sizeof buf,
                  "scenario %s: the %s loop ends farther from the reference than it started "
                  "(|X1| = %.3g %s at t = %.3f s against %.3g at t = 0%s): it does not hold the "
                  "vehicle there, whatever its score",
                  sc.name.c_str(), tuned.label.c_str(), end,
                  kind ? kind->position_unit.c_str() : "", tr.t(last), start, why);
    out.emplace_back(buf);
  }
  if (r.comparison.size() < 2) return out;
  const double best = tuned.outcome.evaluation.objective;
  const double spread = r.noise_floor ? r.noise_floor->relative_spread : 0.0;
  const std::string label = objective_label(r.job);  // metric, window and aggregate
  // "Tuned" is the best of one controller type within the search bounds, not the best
  // controller: a compared controller that scores lower says so.
  // (Not one that breaks the job's hard goals: the job does not allow it, whatever it scores.)
  for (const ComparedController& c : r.comparison) {
    if (c.role != "compare" || !c.outcome.evaluation.feasible()) continue;
    const double v = c.outcome.evaluation.objective;
    if (!(v < best) || !std::isfinite(best)) continue;
    const double margin = (best - v) / best;
    std::snprintf(buf, sizeof buf,
                  "%s (compared) scores %s = %.4g, %.3g %% below the %s's %.4g (%s the noise "
                  "floor of %.2g %%): the tuned gains are the best found for %s within the "
                  "search bounds, not the best controller of the comparison.",
                  c.label.c_str(), label.c_str(), v, 100 * margin, tuned.label.c_str(), best,
                  margin > spread ? "beyond" : "inside", 100 * spread,
                  display_name(r.job.controller.type).c_str());
    out.emplace_back(buf);
  }
  // A tuned objective that beats the job's own controller's only within the noise floor is no
  // improvement the run can claim (SPEC §14): the two cannot be told apart.
  const double own = r.baseline().outcome.evaluation.objective;
  if (!r.front && r.noise_floor && std::isfinite(best) && best > 0 && own > best &&
      (own - best) / best <= spread) {
    std::snprintf(buf, sizeof buf,
                  "The tuned gains beat the job's own on %s only inside the noise floor: %.6g "
                  "against %.6g, %.3g %% apart, where nudging the initial state moves the tuned "
                  "objective by up to %.2g %%; this is no improvement to claim, so keep the "
                  "job's gains or widen the search.",
                  label.c_str(), best, own, 100 * (own - best) / best, 100 * spread);
    out.emplace_back(buf);
  }
  // Until the objective can price control activity: gains that buy their score with much more
  // chattering than the job's own are named (on the listed scenarios, summed).
  // (Over scenarios as the metrics record says the control TV combines: summed.)
  const ComparedController& base = r.baseline();
  const sim::MetricField& tv = sim::metric_field("control_tv");
  const auto listed_tv = [&](const ComparedController& c) {
    std::vector<double> v;
    const std::vector<sim::Metrics>& runs = c.outcome.evaluation.scenarios;
    for (std::size_t i = 0; i < r.listed_scenarios && i < runs.size(); ++i)
      v.push_back(runs[i].*tv.per_run);
    return sim::over_scenarios(tv, v);
  };
  const double tv_tuned = listed_tv(tuned), tv_base = listed_tv(base);
  const double tv_ratio = r.job.metrics && r.job.metrics->control_tv_warning
                              ? *r.job.metrics->control_tv_warning
                              : kControlTvWarningRatio;
  // A job with a goal on the control TV prices it: a hard goal caps it (the tuned gains meet the
  // cap, or are infeasible and say so), and a soft goal trades it against the others by the
  // job's choice; then "the objective does not price control activity" would be false.
  const GoalConfig* tv_goal = nullptr;
  for (const GoalConfig& g : r.job.goals)
    if (g.metric == &tv && (!tv_goal || g.at_most)) tv_goal = &g;
  if (std::isfinite(tv_base) && tv_base > 0 && tv_tuned > tv_ratio * tv_base &&
      !(tv_goal && tv_goal->at_most)) {
    std::snprintf(buf, sizeof buf,
                  "The tuned gains raise the control TV (sum of |u_k - u_{k-1}|, a measure of "
                  "chattering) %.3g times over the job's own gains on the listed scenario%s "
                  "(%.4g against %.4g): %s",
                  tv_tuned / tv_base, r.listed_scenarios == 1 ? "" : "s", tv_tuned, tv_base,
                  tv_goal ? "the job minimizes the control TV as a goal, so this is a trade-off "
                            "its goals chose; check actuator wear and bandwidth before using them."
                          : "the objective does not price control activity, so check actuator "
                            "wear and bandwidth before using them.");
    out.emplace_back(buf);
  }
  return out;
}

std::int64_t finishing_evaluations(const Job& job, std::size_t front_points) {
  const auto compared = static_cast<std::int64_t>(job.compare.size()) + 2;
  // With sensors the noise floor runs twice as many: nudged states, then other sensor seeds
  // (TuningProblem::has_sensors).
  if (job.tuning && job.tuning->noise_floor == FrontNoiseFloor::picked) front_points = 1;
  return compared + (job.reads_sensors() ? 2 : 1) *
                        static_cast<std::int64_t>(NoiseFloor{}.repeats) *
                        static_cast<std::int64_t>(std::max<std::size_t>(1, front_points));
}

std::int64_t comparison_record_every(const Job& job, std::int64_t max_rows) {
  std::int64_t every = std::max<std::int64_t>(
      1, std::llround(kComparisonRecordInterval / job.scenarios.front().sample_time));
  // Rows are the samples k with k % every == 0: ceil(samples / every) of them.
  if (max_rows > 0)
    for (const sim::Scenario& s : job.scenarios)
      every = std::max(every, (s.samples() + max_rows - 1) / max_rows);
  return every;
}

namespace {

// Within 0.1 % of the search range (in ln x on a log scale) from a bound.
bool near(const ParameterBounds& b, double x, bool upper) {
  const bool log = b.scale == Scale::log;
  const auto c = [&](double v) { return log ? sim::math::log(v) : v; };
  const double tol = 1e-3 * (c(b.upper) - c(b.lower));
  return upper ? c(b.upper) - c(x) <= tol : c(x) - c(b.lower) <= tol;
}

}  // namespace

std::optional<double> inward_value(const ParameterBounds& b, double x) {
  const bool at_upper = near(b, x, true), at_lower = near(b, x, false);
  if (at_upper == at_lower) return std::nullopt;  // at neither (or a range too narrow to say)
  if (b.scale == Scale::log)
    return x * sim::math::exp((at_upper ? -0.01 : 0.01) *
                              (sim::math::log(b.upper) - sim::math::log(b.lower)));
  return x + (at_upper ? -0.01 : 0.01) * (b.upper - b.lower);
}

std::vector<std::string> bound_warnings(const Job& job, const Decision& x) {
  return bound_warnings(job, x, {}, 0.0);
}

std::vector<std::string> bound_warnings(const Job& job, const Decision& x,
                                        const std::vector<std::optional<double>>& inward_change,
                                        double noise_floor) {
  std::vector<std::string> out;
  if (!job.tuning) return out;
  const std::vector<ParameterBounds>& ps = job.tuning->parameters;
  for (std::size_t j = 0; j < ps.size() && j < x.size(); ++j) {
    const ParameterBounds& b = ps[j];
    const bool log = b.scale == Scale::log;
    const auto c = [&](double v) { return log ? sim::math::log(v) : v; };
    const double tol = 1e-3 * (c(b.upper) - c(b.lower));
    const bool at_lower = c(x[j]) - c(b.lower) <= tol, at_upper = c(b.upper) - c(x[j]) <= tol;
    if (!at_lower && !at_upper) continue;
    const double bound = at_upper ? b.upper : b.lower;
    // Can the bound move? Not when it is the field's own limit (Ki ≥ 0, say).
    const sim::ControllerField* f = sim::find_controller_field(b.name);
    // A step just past the bound (a millionth of the range) tells whether the field allows it.
    const double step = 1e-6 * (b.upper - b.lower);
    const double beyond = at_upper ? bound + step : (log ? bound * (1 - 1e-6) : bound - step);
    const bool can_widen = f && sim::check_controller_value(job.controller, *f, beyond).empty();
    char buf[400];
    std::snprintf(buf, sizeof buf,
                  "%s = %.6g ended at its %s bound %.6g (within 0.1 %% of the range)%s",
                  b.name.c_str(), x[j], at_upper ? "upper" : "lower", bound,
                  can_widen ? "; the optimum may lie beyond it: widen tuning.parameters." : "");
    std::string w = buf;
    w += can_widen ? b.name + " and run again." : ", which is the field's own limit.";
    if (j < inward_change.size() && inward_change[j]) {
      const double change = *inward_change[j];
      const bool flat = change <= noise_floor;
      std::snprintf(buf, sizeof buf,
                    "%s = %.6g ended at its %s bound %.6g (within 0.1 %% of the range), where the "
                    "objective is flat within the noise: 1 %% of the range inward changes it by "
                    "%.2g %%, inside the noise floor of %.2g %%: the objective cannot tell %s "
                    "values apart there, so widening the bound is unlikely to help.",
                    b.name.c_str(), x[j], at_upper ? "upper" : "lower", bound, 100 * change,
                    100 * noise_floor, b.name.c_str());
      if (flat && can_widen)
        w = buf;
      else if (!flat) {
        std::snprintf(buf, sizeof buf,
                      " (1 %% of the range inward changes the objective by %.2g %%, beyond the "
                      "noise floor of %.2g %%.)",
                      100 * change, 100 * noise_floor);
        w += buf;
      }
    }
    out.push_back(std::move(w));
  }
  return out;
}

std::string noise_floor_sentence(const TuningOutcome& r) {
  if (!r.noise_floor || r.comparison.size() < 2) return "";
  const double base = r.baseline().outcome.evaluation.objective;
  const double best = r.best().outcome.evaluation.objective;
  const double spread = r.noise_floor->relative_spread;
  char buf[480];
  if (!std::isfinite(best) || !std::isfinite(spread)) {
    std::snprintf(buf, sizeof buf,
                  "The noise floor is undefined: the tuned controller's objective is not finite.");
    return buf;
  }
  if (!std::isfinite(base)) {
    std::snprintf(buf, sizeof buf,
                  "The job's own controller diverges; the tuned one does not (its objective moves "
                  "by %.2g %% when the initial state is nudged by a relative %.0e%s).",
                  100 * spread, r.noise_floor->perturbation,
                  r.noise_floor->sensor_seeds.empty() ? "" : " or the sensor seed changes");
    return buf;
  }
  // The decision compares like with like: the margin and the spread relative to the winner.
  const double margin = (base - best) / best;
  const bool outside = std::abs(margin) > spread;
  // Both figures are relative to the tuned objective, so the sentence compares what it decides
  // on; a margin of a factor of two or more reads better as a ratio.
  char amount[160];
  if (std::max(base, best) > 2 * std::min(base, best))
    std::snprintf(amount, sizeof amount,
                  "The tuned objective is %.3g times %s than the job's own "
                  "controller's",
                  std::max(base, best) / std::min(base, best), margin >= 0 ? "smaller" : "larger");
  else
    std::snprintf(amount, sizeof amount,
                  "The job's own controller's objective is %.3g %% %s the tuned one's",
                  100 * std::abs(margin), margin >= 0 ? "above" : "below");
  const NoiseFloor& nf = *r.noise_floor;
  if (!nf.sensor_seeds.empty()) {
    std::snprintf(buf, sizeof buf,
                  "%s; nudging the initial state by a relative %.0e moves the tuned objective by "
                  "up to %.2g %% and other sensor seeds by up to %.2g %% (%d runs each; %.2g %% "
                  "over both), so the %s is %s the noise floor.",
                  amount, nf.perturbation, 100 * nf.rounding_spread, 100 * nf.sensor_spread,
                  nf.repeats, 100 * spread, margin >= 0 ? "improvement" : "difference",
                  outside ? "larger than" : "inside (not merit)");
    return buf;
  }
  std::snprintf(buf, sizeof buf,
                "%s; nudging the initial state by a relative %.0e moves the tuned objective by up "
                "to %.2g %% (%d runs), so the %s is %s the noise floor.",
                amount, nf.perturbation, 100 * spread, nf.repeats,
                margin >= 0 ? "improvement" : "difference",
                outside ? "larger than" : "inside (not merit)");
  return buf;
}

TuningOutcome tune(const Job& job, BatchEvaluator& evaluator, const RunOptions& options) {
  if (!job.tuning) throw InputError("job " + job.name, "/tuning", "is required to tune");
  const TuningProblem problem(job);
  const std::uint64_t seed = options.seed.value_or(job.tuning->seed);
  const AlgorithmPtr& algorithm = job.tuning->algorithm;
  const std::unique_ptr<Optimizer> optimizer = make_optimizer(problem, *algorithm, seed);
  return tune(problem, *optimizer, algorithm, seed, evaluator, options);
}

TuningOutcome checkpoint_outcome(const Job& job, const nlohmann::json& checkpoint,
                                 std::optional<std::uint64_t> seed) {
  if (!job.tuning) throw InputError("job " + job.name, "/tuning", "is required to tune");
  const TuningProblem problem(job);
  TuningOutcome r;
  r.job = job;
  r.job_sha256 = canonical_job_sha256(job);
  r.seed = seed.value_or(job.tuning->seed);
  r.algorithm = job.tuning->algorithm;
  describe_problem(problem, r);
  const std::unique_ptr<Optimizer> optimizer = make_optimizer(problem, *r.algorithm, r.seed);
  const bool with_trials = checkpoint.is_object() && checkpoint.contains("optimizer");
  try {
    optimizer->restore(with_trials ? checkpoint["optimizer"] : checkpoint);
  } catch (const nlohmann::json::exception& e) {
    throw InputError("checkpoint", "", std::string("damaged optimiser state: ") + e.what());
  }
  if (with_trials)
    r.trials = trials_from_json(checkpoint.value("trials", nlohmann::json()), job.goals.size());
  if (optimizer->history().empty())
    throw InputError("checkpoint", "/optimizer/history", "has no iteration");
  const HistoryRow& last = optimizer->history().back();
  r.tuned_controller = problem.controller_for(last.best);
  r.optimization.best = problem.to_parameters(last.best);
  r.optimization.best_fitness = last.best_fitness;
  r.optimization.evaluations = last.evaluations;
  r.optimization.completed = optimizer->iteration() == optimizer->iterations();
  for (HistoryRow h : optimizer->history()) {
    h.best = problem.to_parameters(h.best);
    r.optimization.history.push_back(std::move(h));
  }
  return r;
}

void compare_best(TuningOutcome& r, BatchEvaluator& evaluator, std::int64_t max_trajectory_rows) {
  if (!r.comparison.empty() || r.optimization.history.empty()) return;
  const TuningProblem problem(r.job);
  r.threads = evaluator.concurrency();
  r.threads_per_rank = evaluator.threads_per_rank();
  r.evaluator = evaluator.name();
  compare_with(problem, r, evaluator, max_trajectory_rows);
}

}  // namespace ftc::tune
