#include "ftc/tune/run/documents.hpp"

#include <sys/resource.h>

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <limits>
#include <sstream>

#include "ftc/runtime/controller_json.hpp"
#include "ftc/runtime/scenario_json.hpp"
#include "ftc/sim/controllers.hpp"
#include "ftc/sim/metrics_record.hpp"
#include "ftc/tune/io/files.hpp"
#include "ftc/tune/job/ensemble.hpp"
#include "ftc/version.hpp"
#include "io/decimal.hpp"
#include "io/text.hpp"

namespace ftc::tune {

using nlohmann::json;

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// A number cell of trials.csv and history.csv, with its leading comma: round-trip digits, and
// nothing for an undefined value, so that a CSV reader sees a number column with a gap.
std::string csv_cell(double v) {
  return std::isnan(v) ? std::string(",") : "," + detail::format_number(v, "%.17g");
}

// The tuned parameters in decision-vector order.
std::vector<std::string> parameter_names(const Job& job) {
  std::vector<std::string> names;
  if (job.tuning)
    for (const ParameterBounds& b : job.tuning->parameters) names.push_back(b.name);
  return names;
}

json named(const std::vector<std::string>& names, const Decision& x) {
  json j = json::object();
  for (std::size_t i = 0; i < names.size() && i < x.size(); ++i) j[names[i]] = x[i];
  return j;
}

}  // namespace

std::string measure_label(std::size_t n, const std::string& metric, const ObjectiveConfig& o,
                          bool windowed) {
  const auto seconds = [](double t) { return detail::format_number(t, "%.6g") + " s"; };
  std::string window;
  if (o.window_from == WindowFrom::first_fault)
    window =
        (o.window.t0 == 0 ? std::string("first fault") : "first fault + " + seconds(o.window.t0)) +
        ", " + (std::isfinite(o.window.t1) ? "+" + seconds(o.window.t1) : std::string("end"));
  else
    window = seconds(o.window.t0) + ", " +
             (std::isfinite(o.window.t1) ? seconds(o.window.t1) : std::string("end"));
  const std::string value = windowed ? metric + "[" + window + "]" : metric;
  if (n <= 1) return value;
  std::string aggregate;
  switch (o.aggregate) {
    case Aggregate::mean:
      aggregate = "mean";
      break;
    case Aggregate::max:
      aggregate = "max";
      break;
    case Aggregate::quantile:
      aggregate = "quantile" + detail::format_number(o.q, "%.3g");
      break;
    case Aggregate::cvar:
      aggregate = "CVaR" + detail::format_number(o.alpha, "%.3g");
      break;
  }
  return aggregate + " of " + value + " over " + std::to_string(n) + " scenarios";
}

std::string objective_label(const Job& job) {
  return measure_label(job.scenario_count(), sim::plain_label(*job.objective.metric), job.objective,
                       true);
}

std::string fitness_label(const Job& job) {
  if (job.goals.empty()) return objective_label(job);
  std::string soft;
  std::size_t n = 0;
  for (const GoalConfig& g : job.goals)
    if (g.soft()) {
      soft +=
          (n++ ? " and " : "") + measure_label(job.scenario_count(), sim::plain_label(*g.metric),
                                               g.measure(), g.windowed());
    }
  return n >= 2 ? "front of " + soft : soft;
}

std::string goal_label(const Job& job, std::size_t k, std::size_t scenarios) {
  const GoalConfig& g = job.goals.at(k);
  // The metric's label, as the front and the objective word it ("control TV", "peak command
  // [0 s, end]"), where comparison.md once had the name in capitals.
  return measure_label(scenarios ? scenarios : job.scenario_count(), sim::plain_label(*g.metric),
                       g.measure(), g.windowed()) +
         (g.at_most ? " <= " + detail::format_number(*g.at_most, "%.6g") : ", minimized");
}

json goals_json(const Job& job, const std::vector<double>& values, double violation) {
  json list = json::array();
  for (std::size_t k = 0; k < job.goals.size(); ++k) {
    json goal = to_json(job.goals[k]);
    const double v = k < values.size() ? values[k] : std::numeric_limits<double>::quiet_NaN();
    goal["value"] = json_number(v);
    if (job.goals[k].at_most) goal["violation"] = json_number(job.goals[k].violation(v));
    list.push_back(std::move(goal));
  }
  return {{"goals", std::move(list)},
          {"total_violation", json_number(violation)},
          {"feasible", !(violation > 0)}};
}

std::string label_slug(const std::string& label) {
  std::string slug;
  for (char c : label) {
    const bool keep = std::isalnum(static_cast<unsigned char>(c));
    if (keep)
      slug += static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    else if (!slug.empty() && slug.back() != '-')
      slug += '-';
  }
  while (!slug.empty() && slug.back() == '-') slug.pop_back();
  return slug;
}

std::string trajectory_file(const TuningOutcome& r, std::size_t controller, std::size_t scenario) {
  char index[24];
  std::snprintf(index, sizeof index, "%02zu-", controller + 1);
  return "trajectories/" + r.job.scenarios.at(scenario).name + "/" + index +
         label_slug(r.comparison.at(controller).label) + ".csv";
}

json summary_json(const Summary& s) {
  return {{"scenarios", s.scenarios},
          {"counted", s.counted},
          {"unrecoverable", s.unrecoverable},
          {"diverged", s.diverged},
          {"mean", json_number(s.mean)},
          {"median", json_number(s.median)},
          {"p90", json_number(s.p90)},
          {"p99", json_number(s.p99)},
          {"max", json_number(s.max)},
          {"cvar", json_number(s.cvar)},
          {"objective", json_number(s.objective)}};
}

json gains_document(const TuningOutcome& r) {
  const Job& job = r.job;
  // Without a comparison (a running job's best so far, which the service serves from what the
  // run stored rather than simulating in the request): the best's values are its trial's, as
  // the run recorded them. A trial's results are a function of its parameters, so any uncapped
  // trial with the best's parameters, to the bit, is the best's record.
  const bool stored = r.comparison.empty();
  const Trial* record = nullptr;
  if (stored)
    for (auto t = r.trials.rbegin(); t != r.trials.rend() && !record; ++t)
      if (!t->capped && t->parameters == r.optimization.best) record = &*t;
  const double best_objective = stored ? (record ? record->objective : kNaN)
                                       : r.best().outcome.evaluation.objective;
  json g;
  g["schema"] = kGainsSchema;
  g["controller"] = to_json(r.tuned_controller);
  g["tuned"] = json::object();
  if (stored) {
    const std::vector<std::string> names = parameter_names(job);
    for (std::size_t k = 0; k < names.size() && k < r.optimization.best.size(); ++k)
      g["tuned"][names[k]] = r.optimization.best[k];
  }
  for (const auto& [name, value] : r.tuned) g["tuned"][name] = value;
  g["sample_time"] = job.scenarios.front().sample_time;
  g["plant"] = to_json(job.plant);
  if (const auto a = job.tuned_acceleration())
    g["acceleration"] = runtime::acceleration_shape()->write(*a);
  json objective = to_json(job.objective);
  objective["value"] = json_number(best_objective);
  if (job.ensemble)  // what the value is taken over
    objective["scenarios"] = {{"listed", r.listed_scenarios},
                              {"members", r.scenarios - r.listed_scenarios},
                              {"unrecoverable", r.unrecoverable},
                              {"left_out", r.left_out}};
  g["objective"] = objective;
  g["fitness"] = json_number(r.optimization.best_fitness);
  if (!job.goals.empty()) {  // the winner's goals, and the rule that chose it
    if (!stored) {
      const Evaluation& e = r.best().outcome.evaluation;
      g["goals"] = goals_json(job, e.goals, e.violation);
    } else {
      g["goals"] = record ? goals_json(job, record->goals, record->violation)
                          : goals_json(job, std::vector<double>(job.goals.size(), kNaN), kNaN);
    }
    g["goals"]["rule"] =
        "feasible beats infeasible; between feasible candidates the soft goal decides, between "
        "infeasible ones the lesser total violation";
    const bool hard = std::any_of(job.goals.begin(), job.goals.end(),
                                  [](const GoalConfig& goal) { return !goal.soft(); });
    if (r.front && r.front->points.empty())
      g["goals"]["rule"] =
          hard ? "no trial met the hard goals, so the Pareto front (front.json) is empty and no "
                 "point was picked: these are the gains of the trial with the least total "
                 "violation of the hard goals"
               : "no trial had a finite value of every soft goal (each diverged, or a goal is "
                 "undefined on these scenarios), so the Pareto front (front.json) is empty and no "
                 "point was picked: these are the gains of the run's best trial by its fitness";
    if (r.front && !r.front->points.empty()) {
      g["goals"]["rule"] = front_rule_text(*r.front);
      g["goals"]["front"] = {{"index", r.front->picked},
                             {"rule", r.front->rule},
                             {"points", r.front->points.size()},
                             {"trial", r.front->points[r.front->picked].trial}};
    }
  }
  if (stored) {
    g["baseline"] = {{"controller", to_json(job.controller)}, {"objective", nullptr},
                     {"fitness", nullptr}};
  } else {
    const ComparedController& base = r.baseline();
    g["baseline"] = {{"controller", to_json(base.controller)},
                     {"objective", json_number(base.outcome.evaluation.objective)},
                     {"fitness", json_number(base.outcome.evaluation.fitness)}};
  }
  json optimizer = r.algorithm->to_json();
  optimizer["seed"] = r.seed;
  optimizer["evaluations"] = r.optimization.evaluations;
  // A best without its comparison is no run's answer yet, even after the last iteration: the
  // loader must refuse it as it refuses a stopped run's.
  optimizer["completed"] = r.optimization.completed && !stored;
  g["optimizer"] = optimizer;
  const std::vector<std::string> names = parameter_names(job);
  g["history"] = json::array();
  for (const HistoryRow& h : r.optimization.history) {
    json row = {{"iteration", h.iteration},
                {"best_fitness", json_number(h.best_fitness)},
                {"best", named(names, h.best)},
                {"evaluations", h.evaluations}};
    for (const auto& [name, value] : h.extras) row[name] = json_number(value);
    g["history"].push_back(std::move(row));
  }
  if (r.noise_floor) {
    const NoiseFloor& n = *r.noise_floor;
    g["noise_floor"] = {{"perturbation", n.perturbation},
                        {"repeats", n.repeats},
                        {"objective_min", json_number(n.objective_min)},
                        {"objective_max", json_number(n.objective_max)},
                        {"relative_spread", json_number(n.relative_spread)}};
    if (!n.sensor_seeds.empty()) {
      g["noise_floor"]["sensor_seeds"] = n.sensor_seeds;
      g["noise_floor"]["rounding_spread"] = json_number(n.rounding_spread);
      g["noise_floor"]["sensor_spread"] = json_number(n.sensor_spread);
    }
  }
  // Only when there is something to say: a runtime loader from before this key exists would
  // refuse every file that has it.
  if (stored) {
    json w = r.warnings;
    w.push_back(kStoredBestWarning);
    g["warnings"] = std::move(w);
  } else if (!r.warnings.empty()) {
    g["warnings"] = r.warnings;
  }
  g["job"] = {{"name", job.name}, {"sha256", r.job_sha256}};
  g["generator"] = {{"name", kToolName}, {"version", kVersion}};
  return g;
}

std::string trials_csv(const TuningOutcome& r) {
  const std::vector<std::string> names = parameter_names(r.job);
  std::string s = "iteration,index";
  for (const std::string& n : names) s.append(",").append(n);
  s += ",objective,fitness,diverged,accepted,capped,simulated,cached";
  if (!r.job.ensemble)
    for (const sim::Scenario& sc : r.job.scenarios) s.append(",objective_").append(sc.name);
  for (std::size_t k = 0; k < r.job.goals.size(); ++k)
    s.append(",goal" + std::to_string(k) + "_" + std::string(r.job.goals[k].metric->name));
  if (!r.job.goals.empty()) s += ",violation,feasible";
  s += '\n';
  const auto num = [&](double v) { s += csv_cell(v); };
  for (const Trial& t : r.trials) {
    s.append(std::to_string(t.iteration)).append(",").append(std::to_string(t.index));
    for (double v : t.parameters) num(v);
    num(t.objective);
    num(t.fitness);
    s.append(",").append(std::to_string(t.diverged)).append(t.accepted ? ",1" : ",0");
    // Capping (issue 27): a capped trial's objective is a lower bound (its fitness an upper
    // one) after `simulated` of the candidate's scenarios; the values it has not are empty.
    // The cache (issue 43): a cached row simulated nothing; its values are those of the first
    // row with the same parameters.
    s.append(t.capped ? ",1," : ",0,")
        .append(std::to_string(t.cached   ? 0
                               : t.capped ? t.simulated
                                          : r.job.scenario_count()))
        .append(t.cached ? ",1" : ",0");
    if (t.capped && !r.job.ensemble) s.append(r.job.scenarios.size(), ',');
    for (double v : t.scenario_objectives) num(v);
    if (!r.job.goals.empty()) {
      // A capped trial's goals and violation are lower bounds (a goal without one empty), and
      // its feasibility is known only when the bound of its violation is above 0.
      for (double v : t.goals) {
        if (t.capped && std::isnan(v))
          s += ',';
        else
          num(v);
      }
      num(t.violation);
      s.append(t.violation > 0 ? ",0" : t.capped ? "," : ",1");
    }
    s += '\n';
  }
  return s;
}

std::string history_csv(const TuningOutcome& r) {
  const std::vector<std::string> columns = r.algorithm->history_columns();
  std::string s = "iteration,best_fitness";
  for (const std::string& n : parameter_names(r.job)) s += "," + n;
  for (const std::string& c : columns) s += "," + c;
  s += ",evaluations";
  if (r.front) s += ",hypervolume";  // of the front so far, against front.json's reference point
  s += "\n";
  const auto cell = csv_cell;
  for (const HistoryRow& h : r.optimization.history) {
    s += std::to_string(h.iteration) + cell(h.best_fitness);
    for (double v : h.best) s += cell(v);
    for (const std::string& c : columns) {
      double v = std::numeric_limits<double>::quiet_NaN();
      for (const auto& [name, value] : h.extras)
        if (name == c) v = value;
      s += cell(v);
    }
    s.append(",").append(std::to_string(h.evaluations));
    if (r.front) {
      const auto i = static_cast<std::size_t>(h.iteration);
      s += cell(i < r.hypervolume.size() ? r.hypervolume[i]
                                         : std::numeric_limits<double>::quiet_NaN());
    }
    s.append("\n");
  }
  return s;
}

json comparison_document(const TuningOutcome& r) {
  json doc;
  doc["job"] = r.job.name;
  doc["objective"] = to_json(r.job.objective);
  doc["objective"]["label"] = objective_label(r.job);
  doc["scenarios"] = json::array();
  for (const sim::Scenario& s : r.job.scenarios) doc["scenarios"].push_back(s.name);
  // What each listed scenario's controller read (SensorModel::summary), when any has sensors.
  for (const sim::Scenario& s : r.job.scenarios)
    if (s.sensors) doc["sensors"][s.name] = s.sensors->summary();
  doc["controllers"] = json::array();
  for (const ComparedController& c : r.comparison) {
    json cj;
    cj["label"] = c.label;
    cj["role"] = c.role;
    cj["controller"] = to_json(c.controller);
    cj["objective"] = json_number(c.outcome.evaluation.objective);
    cj["fitness"] = json_number(c.outcome.evaluation.fitness);
    // A job with goals: each goal's value over the job's scenarios (members included), as the
    // search saw it, its limit and violation, and whether the controller meets every limit.
    if (!r.job.goals.empty())
      cj["goals"] = goals_json(r.job, c.outcome.evaluation.goals, c.outcome.evaluation.violation);
    if (!c.outcome.error.empty()) cj["error"] = c.outcome.error;
    cj["scenarios"] = json::array();
    // The listed scenarios in full; an ensemble's members in its summary below.
    for (std::size_t i = 0; i < r.listed_scenarios && i < c.outcome.evaluation.scenarios.size();
         ++i) {
      json m = metrics_json(c.outcome.evaluation.scenarios[i]);
      m["name"] = r.job.scenarios[i].name;
      if (i < r.listed_recoverable.size())
        m["recoverable"] = static_cast<bool>(r.listed_recoverable[i]);
      // A model valid only in part of the state space says whether this run left it; its
      // metrics still count (the same field as `simulate`'s metrics.json).
      if (i < c.outcome.model_invalid.size() && c.outcome.model_invalid[i])
        m["model_invalid"] = *c.outcome.model_invalid[i];
      if (i < c.outcome.trajectories.size())
        m["trajectory"] = trajectory_file(r, static_cast<std::size_t>(&c - r.comparison.data()), i);
      cj["scenarios"].push_back(m);
    }
    if (r.job.ensemble) cj["ensemble"] = summary_json(c.summary);
    doc["controllers"].push_back(cj);
  }
  if (const std::string s = noise_floor_sentence(r); !s.empty()) doc["noise_floor"] = s;
  return doc;
}

std::string comparison_markdown(const TuningOutcome& r) {
  std::ostringstream o;
  const Job& job = r.job;
  o << "# " << job.name << ": controllers compared\n\n";
  o << "Tuned:";
  for (const auto& [name, value] : r.tuned)
    o << " " << name << " = " << detail::format_number(value, "%.6g");
  o << " (fitness J = " << detail::format_number(r.optimization.best_fitness, "%.6g") << ", "
    << r.optimization.evaluations << " evaluations, seed " << r.seed << ").\n\n";
  o << "Objective: " << objective_label(job) << " (window ["
    << detail::format_number(job.objective.window.t0) << ", "
    << (std::isfinite(job.objective.window.t1) ? detail::format_number(job.objective.window.t1)
                                               : std::string("end"))
    << ") s"
    << (job.objective.window_from == WindowFrom::first_fault ? " from each scenario's first fault"
                                                             : " from each scenario's start")
    << (job.scenario_count() > 1
            ? std::string(", ") + to_string(job.objective.aggregate) + " over scenarios"
            : std::string())
    << ").\n";
  if (const std::string nf = noise_floor_sentence(r); !nf.empty()) o << "\n" << nf << "\n";
  // What the controller read, where it was not the exact state (the metrics measure the truth).
  for (const sim::Scenario& s : job.scenarios)
    if (s.sensors)
      o << "\nSensors of scenario " << s.name << ": " << s.sensors->summary() << ".\n";
  if (!job.goals.empty()) {
    o << "\n## Goals\n\nEach goal's value per controller, aggregated over the scenarios as the "
         "search aggregates it; a controller is feasible when it meets every limit.\n\n"
         "| controller |";
    for (std::size_t k = 0; k < job.goals.size(); ++k) o << " " << goal_label(job, k) << " |";
    o << " total violation | feasible |\n|---|";
    for (std::size_t k = 0; k < job.goals.size(); ++k) o << "---:|";
    o << "---:|:---:|\n";
    for (const ComparedController& c : r.comparison) {
      const Evaluation& e = c.outcome.evaluation;
      o << "| " << c.label << " |";
      for (std::size_t k = 0; k < job.goals.size(); ++k)
        o << " "
          << detail::format_number(k < e.goals.size() ? e.goals[k]
                                                      : std::numeric_limits<double>::quiet_NaN())
          << " |";
      o << " " << detail::format_number(e.violation) << " | " << (e.feasible() ? "yes" : "no")
        << " |\n";
    }
  }
  if (job.ensemble) {
    o << "\n## All " << r.scenarios << " scenarios (" << r.listed_scenarios << " listed, "
      << r.scenarios - r.listed_scenarios << " ensemble members, seed " << job.ensemble->seed
      << ")\n\n"
      << r.unrecoverable << " cannot be controlled by any gains once their faults have started"
      << (r.left_out > 0 ? ", and the objective leaves them out" : "") << ". Values are "
      << job.objective.metric->name << " per scenario; quantiles by nearest rank.\n\n"
      << "| controller | " << objective_label(job) << " | mean | median | p90 | max | CVaR"
      << detail::format_number(job.objective.alpha, "%.3g") << " | diverged |\n"
      << "|---|---:|---:|---:|---:|---:|---:|---:|\n";
    for (const ComparedController& c : r.comparison) {
      const Summary& m = c.summary;
      o << "| " << c.label << " | " << detail::format_number(m.objective) << " | "
        << detail::format_number(m.mean) << " | " << detail::format_number(m.median) << " | "
        << detail::format_number(m.p90) << " | " << detail::format_number(m.max) << " | "
        << detail::format_number(m.cvar) << " | " << m.diverged << " |\n";
    }
  }
  for (std::size_t s = 0; s < job.scenarios.size(); ++s) {
    const sim::Scenario& sc = job.scenarios[s];
    o << "\n## Scenario " << sc.name << "\n\n";
    std::vector<std::pair<std::string, const sim::Metrics*>> rows;
    for (const ComparedController& c : r.comparison)
      rows.emplace_back(c.label, &c.outcome.evaluation.scenarios.at(s));
    o << metrics_markdown_table(rows);
  }
  o << "\n" << sim::units_note(true) << "\n";
  return o.str();
}

std::map<std::string, std::string> output_files(const TuningOutcome& r) {
  std::map<std::string, std::string> files = {
      {"gains.json", gains_document(r).dump(2) + "\n"},
      {"history.csv", history_csv(r)},
      {"trials.csv", trials_csv(r)},
      {"job.json", to_json(r.job).dump(2) + "\n"},
      {"comparison.json", comparison_document(r).dump(2) + "\n"},
      {"comparison.md", comparison_markdown(r)}};
  for (std::size_t c = 0; c < r.comparison.size(); ++c)
    for (std::size_t s = 0; s < r.comparison[c].outcome.trajectories.size(); ++s)
      files[trajectory_file(r, c, s)] = trajectory_csv(r.comparison[c].outcome.trajectories[s]);
  if (r.front) {
    files["front.json"] = front_document(r.job, r.job_sha256, r.seed, *r.front).dump(2) + "\n";
    files["front.csv"] = front_csv(r.job, *r.front);
  }
  return files;
}

std::string run_summary(const json& gains, const json& comparison, const json& run,
                        const std::string& where) {
  std::string out;
  char buf[256];
  const auto number = [](const json& v) {  // null: a diverged value (json_number's inf)
    return v.is_number() ? v.get<double>() : std::numeric_limits<double>::infinity();
  };
  // A job lists its tuned parameters in the controller table's order (parse_job).
  std::string values;
  const json& tuned = gains.at("tuned");
  for (const sim::ControllerField& f : sim::controller_fields())
    if (tuned.contains(f.name)) {
      std::snprintf(buf, sizeof buf, "%s%s = %.5g", values.empty() ? "" : ", ", f.name,
                    number(tuned[f.name]));
      values += buf;
    }
  const auto type = sim::controller_type_from_string(gains["controller"].value("type", ""));
  out += "tuned " + (type ? display_name(*type) : std::string("controller")) + ": " + values +
         "\n";
  // The objective with seven digits and the change in %: J to six digits can read the same
  // while the gains and the objective move.
  const double best = number(gains["objective"]["value"]);
  const double base = number(gains["baseline"]["objective"]);
  const std::string label =
      comparison.contains("objective")
          ? comparison["objective"].value("label", std::string("objective"))
          : gains["objective"].value("metric", std::string("objective"));
  std::snprintf(buf, sizeof buf, "  %s = %.6e (job's own controller: %.6e", label.c_str(), best,
                base);
  out += buf;
  // Relative to the tuned objective, as the noise-floor sentence below and the compared
  // controllers' warnings give it; from a factor of two on, as a ratio (a 9 020-fold reduction
  // read "100 % lower").
  if (std::isfinite(best) && std::isfinite(base) && best > 0 && base > 0) {
    if (std::max(base, best) > 2 * std::min(base, best))
      std::snprintf(buf, sizeof buf, ", %.3g times the tuned", base / best);
    else
      std::snprintf(buf, sizeof buf, ", %.3g %% %s the tuned", 100 * std::abs((base - best) / best),
                    base >= best ? "above" : "below");
    out += buf;
  }
  std::snprintf(buf, sizeof buf, "); fitness J = %.6g\n", number(gains["fitness"]));
  out += buf;
  if (gains["objective"].contains("scenarios")) {
    const json& sc = gains["objective"]["scenarios"];
    std::snprintf(buf, sizeof buf,
                  "  over %lld scenarios: %lld listed, %lld ensemble members; %lld "
                  "unrecoverable%s\n",
                  sc.value("listed", 0LL) + sc.value("members", 0LL), sc.value("listed", 0LL),
                  sc.value("members", 0LL), sc.value("unrecoverable", 0LL),
                  sc.value("left_out", 0LL) > 0 ? ", left out of the objective" : "");
    out += buf;
  }
  if (comparison.contains("noise_floor"))
    out += "  " + comparison["noise_floor"].get<std::string>() + "\n";
  const int threads = run.value("threads", 0);
  std::snprintf(buf, sizeof buf, "  %lld simulations on %d thread%s in %.2f s%s\n",
                run.value("simulations", 0LL), threads, threads == 1 ? "" : "s",
                run.value("wall_seconds", 0.0), where.c_str());
  out += buf;
  if (const long long cached = run.value("cached_trials", 0LL); cached > 0) {
    std::snprintf(buf, sizeof buf,
                  "  %lld candidate%s proposed again took %s earlier results (the cache; "
                  "trials.csv marks %s)\n",
                  cached, cached == 1 ? "" : "s", cached == 1 ? "its" : "their",
                  cached == 1 ? "it" : "them");
    out += buf;
  }
  return out;
}

json run_metadata(const TuningOutcome& r, double wall_seconds) {
  rusage ru{};
  const long max_rss_kib = ::getrusage(RUSAGE_SELF, &ru) == 0 ? ru.ru_maxrss : -1;
  return {{"threads", r.threads},
          {"ranks", r.threads_per_rank.size()},
          {"threads_per_rank", r.threads_per_rank},
          {"evaluator", r.evaluator},
          {"wall_seconds", wall_seconds},
          {"simulations", r.simulations},
          // Trials served by the cache (issue 43): candidates not simulated again.
          {"cached_trials", cached_trials(r.trials)},
          {"max_rss_kib", max_rss_kib},
          {"seed", r.seed},
          {"generator", {{"name", kToolName}, {"version", kVersion}}}};
}

std::vector<std::string> write_outputs(const TuningOutcome& r, const std::filesystem::path& dir) {
  return write_output_files(output_files(r), dir);
}

std::vector<std::string> write_output_files(const std::map<std::string, std::string>& files,
                                            const std::filesystem::path& dir) {
  std::vector<std::string> names;
  // gains.json last: a directory that has it holds every other file of the same run.
  for (const auto& [name, content] : files)
    if (name != "gains.json") {
      write_file_atomic(dir / name, content);
      names.push_back(name);
    }
  write_file_atomic(dir / "gains.json", files.at("gains.json"));
  names.push_back("gains.json");
  return names;
}

std::string trajectory_csv(const sim::Trajectory& tr) {
  std::string s = "time";
  for (int i = 1; i <= 2 * tr.axes; ++i) s += ",x" + std::to_string(i);
  for (const char* prefix : {",ud", ",u"})
    for (int j = 1; j <= tr.actuators; ++j) s += prefix + std::to_string(j);
  s += '\n';
  // write_f6 and write_g9 print exactly what printf's %.6f and %.9g print, without parsing a
  // format string or touching the locale per number (io/decimal.cpp says how).
  const std::size_t columns = 1 + 2 * static_cast<std::size_t>(tr.axes + tr.actuators);
  // Room for a row: 24 bytes per %.9g number (io/decimal.hpp) and 330 for the %.6f time.
  const std::size_t row_max = columns * 24 + 330;
  std::size_t used = s.size();
  s.resize(used + tr.rows() * columns * 12 + row_max);
  char* out = s.data() + used;
  for (std::size_t r = 0; r < tr.rows(); ++r) {
    if (s.size() - static_cast<std::size_t>(out - s.data()) < row_max) {
      used = static_cast<std::size_t>(out - s.data());
      s.resize(2 * s.size() + row_max);
      out = s.data() + used;
    }
    const std::span<const double> row = tr.row(r);
    out = detail::write_f6(out, row[0]);
    out = detail::write_g9_list(out, row.data() + 1, row.size() - 1, ',');
    *out++ = '\n';
  }
  s.resize(static_cast<std::size_t>(out - s.data()));
  return s;
}

namespace {
json window_json(const sim::Window& w) { return json::array({w.t0, json_number(w.t1)}); }
}  // namespace

// The columns of the record's description (ftc/sim/metrics_record.hpp): the objective window's
// and the run fields, the extra windows' (those of the first row), then one per fault field and
// onset.
std::string metrics_markdown_table(
    const std::vector<std::pair<std::string, const sim::Metrics*>>& rows) {
  using sim::MetricScope;
  std::ostringstream o;
  if (rows.empty()) return {};
  const sim::Metrics& first = *rows.front().second;
  std::size_t columns = 0;
  const auto head = [&](const auto&... parts) {
    o << " ";
    (o << ... << parts);
    o << " |";
    ++columns;
  };
  o << "| controller |";
  for (const sim::MetricField& f : sim::kMetricFields)
    if (f.in_tables && f.scope != MetricScope::fault) head(f.label);
  for (const sim::MetricField& f : sim::kMetricFields)
    if (f.column_per_extra_window)
      for (const sim::Window& w : first.extra_windows)
        head(f.label, " [", detail::format_number(w.t0), ", ", detail::format_number(w.t1), ")");
  for (const sim::MetricField& f : sim::kMetricFields)
    if (f.in_tables && f.scope == MetricScope::fault)
      for (std::size_t k = 0; k < first.fault_onsets.size(); ++k) head(f.label, " ", k + 1);
  o << "\n|---|";
  for (std::size_t k = 0; k < columns; ++k) o << "---:|";
  o << "\n";
  for (const auto& [label, metrics] : rows) {
    const sim::Metrics& m = *metrics;
    o << "| " << label << (m.diverged ? " (diverged)" : "") << " |";
    const auto cell = [&](double v) { o << " " << detail::format_number(v) << " |"; };
    for (const sim::MetricField& f : sim::kMetricFields) {
      if (!f.in_tables) continue;
      if (f.scope == MetricScope::window) cell(m.errors.*f.in_window);
      if (f.scope == MetricScope::run) cell(m.*f.per_run);
    }
    for (const sim::MetricField& f : sim::kMetricFields)
      if (f.column_per_extra_window)
        for (const sim::ErrorIntegrals& e : m.extra) cell(e.*f.in_window);
    for (const sim::MetricField& f : sim::kMetricFields)
      if (f.in_tables && f.scope == MetricScope::fault)
        for (double p : m.*f.per_fault) cell(p);
    o << "\n";
  }
  return o.str();
}

// From the record's description (ftc/sim/metrics_record.hpp): each field under its name, the
// window fields of the extra windows in "segments".
json metrics_json(const sim::Metrics& m) {
  json j;
  j["window"] = window_json(m.window);
  j["segments"] = json::array();
  for (std::size_t i = 0; i < m.extra.size(); ++i)
    j["segments"].push_back({{"window", window_json(m.extra_windows[i])}});
  for (const sim::MetricField& f : sim::kMetricFields) {
    const std::string name(f.name);
    switch (f.scope) {
      case sim::MetricScope::window:
        j[name] = json_number(m.errors.*f.in_window);
        for (std::size_t i = 0; i < m.extra.size(); ++i)
          j["segments"][i][name] = json_number(m.extra[i].*f.in_window);
        break;
      case sim::MetricScope::run:
        j[name] = json_number(m.*f.per_run);
        break;
      case sim::MetricScope::fault:
        j[name] = json::array();
        for (double v : m.*f.per_fault) j[name].push_back(json_number(v));
        break;
    }
  }
  j["diverged"] = m.diverged;
  if (m.diverged) j["diverged_at"] = m.diverged_at;
  return j;
}

}  // namespace ftc::tune
