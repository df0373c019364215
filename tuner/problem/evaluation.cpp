#include "ftc/tune/problem/evaluation.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <nlohmann/json.hpp>

namespace ftc::tune {

using nlohmann::json;

sim::SimulationOptions simulation_options(const Job& job, const sim::Scenario& scenario,
                                          std::int64_t record_every) {
  sim::SimulationOptions o;
  o.window = job.objective.window;
  o.record_every = record_every;
  std::vector<double> cuts;
  for (const sim::Fault& f : scenario.faults)
    if (f.onset > 0 && f.onset < scenario.duration) cuts.push_back(f.onset);
  std::sort(cuts.begin(), cuts.end());
  cuts.erase(std::unique(cuts.begin(), cuts.end()), cuts.end());
  double start = 0.0;
  for (double c : cuts) {
    o.extra_windows.push_back({start, c});
    start = c;
  }
  o.extra_windows.push_back({start, scenario.duration});
  return o;
}

sim::SimulationResult simulate_scenario(const Job& job, const sim::AnyPlant& plant,
                                        const sim::ControllerConfig& controller,
                                        std::size_t scenario, std::int64_t record_every) {
  const sim::Scenario& s = job.scenarios.at(scenario);
  return plant.simulate(controller, s, simulation_options(job, s, record_every));
}

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

Evaluation score(const ObjectiveConfig& objective, std::vector<sim::Metrics> per_scenario) {
  Evaluation e;
  e.scenarios = std::move(per_scenario);
  for (const sim::Metrics& m : e.scenarios) e.diverged = e.diverged || m.diverged;
  e.objective = aggregate_objective(objective, e.scenarios);
  e.fitness = e.diverged ? 0.0 : fitness_of(e.objective);
  return e;
}

std::string trajectory_csv(const sim::Trajectory& tr) {
  std::string s = "time";
  for (int i = 1; i <= 2 * tr.axes; ++i) s += ",x" + std::to_string(i);
  for (const char* prefix : {",ud", ",u"})
    for (int j = 1; j <= tr.actuators; ++j) s += prefix + std::to_string(j);
  s += '\n';
  s.reserve(tr.rows() * 200);
  char buf[64];
  for (std::size_t r = 0; r < tr.rows(); ++r) {
    const std::span<const double> row = tr.row(r);
    std::snprintf(buf, sizeof buf, "%.6f", row[0]);
    s += buf;
    for (std::size_t i = 1; i < row.size(); ++i) {
      std::snprintf(buf, sizeof buf, ",%.9g", row[i]);
      s += buf;
    }
    s += '\n';
  }
  return s;
}

namespace {
json window_json(const sim::Window& w) { return json::array({w.t0, json_number(w.t1)}); }
}  // namespace

json metrics_json(const sim::Metrics& m) {
  json j;
  j["window"] = window_json(m.window);
  j["ise"] = json_number(m.errors.ise);
  j["iae"] = json_number(m.errors.iae);
  j["itae"] = json_number(m.errors.itae);
  j["max_abs_u"] = m.max_abs_u;
  j["control_tv"] = m.control_tv;
  j["peak_error_after_fault"] = json::array();
  for (double v : m.peak_error_after_fault) j["peak_error_after_fault"].push_back(json_number(v));
  j["diverged"] = m.diverged;
  if (m.diverged) j["diverged_at"] = m.diverged_at;
  j["segments"] = json::array();
  for (std::size_t i = 0; i < m.extra.size(); ++i)
    j["segments"].push_back({{"window", window_json(m.extra_windows[i])},
                             {"ise", json_number(m.extra[i].ise)},
                             {"iae", json_number(m.extra[i].iae)},
                             {"itae", json_number(m.extra[i].itae)}});
  return j;
}

}  // namespace ftc::tune
