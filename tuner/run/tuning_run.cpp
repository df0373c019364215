#include "ftc/tune/run/tuning_run.hpp"

#include <sys/resource.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <sstream>

#include "ftc/runtime/controller_json.hpp"
#include "ftc/tune/io/files.hpp"
#include "ftc/tune/problem/problem.hpp"
#include "ftc/tune/io/sha256.hpp"
#include "ftc/version.hpp"
#include "io/text.hpp"

namespace ftc::tune {

using nlohmann::json;

namespace {

json named(const std::vector<std::string>& names, const Decision& x) {
  json j = json::object();
  for (std::size_t i = 0; i < names.size() && i < x.size(); ++i) j[names[i]] = x[i];
  return j;
}

}  // namespace

std::string display_name(sim::ControllerType t) {
  switch (t) {
    case sim::ControllerType::nftsmc:
      return "NFTSMC";
    case sim::ControllerType::fosmc:
      return "FOSMC";
    case sim::ControllerType::pi_fosmc:
      return "PI-FOSMC";
    case sim::ControllerType::adaptive_neural_pi_fosmc:
      return "adaptive neural PI-FOSMC";
  }
  return "?";
}

std::string canonical_job_sha256(const Job& job) { return sha256_hex(to_json(job).dump()); }

std::string trajectory_file(const TuningOutcome& r, std::size_t controller, std::size_t scenario) {
  std::string slug;
  for (char c : r.comparison.at(controller).label) {
    const bool keep = std::isalnum(static_cast<unsigned char>(c));
    if (keep)
      slug += static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    else if (!slug.empty() && slug.back() != '-')
      slug += '-';
  }
  while (!slug.empty() && slug.back() == '-') slug.pop_back();
  char index[24];
  std::snprintf(index, sizeof index, "%02zu-", controller + 1);
  return "trajectories/" + r.job.scenarios.at(scenario).name + "/" + index + slug + ".csv";
}

TuningOutcome tune(const Job& job, const RunOptions& options) {
  TuningOutcome r;
  r.job = job;
  r.job_sha256 = canonical_job_sha256(job);
  const TuningProblem problem(job);
  r.seed = options.seed.value_or(job.tuning->seed);

  ParallelEvaluator evaluator(problem, options.threads);
  r.threads = evaluator.threads();
  auto optimizer = make_optimizer(job.tuning->algorithm, r.seed, problem.space());
  r.optimization = run_optimizer(*optimizer, evaluator, options.observer, options.resume);
  if (!r.optimization.completed || !options.compare) {
    r.simulations = evaluator.simulations();
    return r;
  }

  r.tuned_controller = problem.controller_for(r.optimization.best);
  for (std::size_t j = 0; j < problem.space().names.size(); ++j)
    r.tuned.emplace_back(problem.space().names[j], r.optimization.best[j]);

  std::vector<sim::ControllerConfig> controllers;
  for (const CompareEntry& c : job.compare) {
    r.comparison.push_back({c.label, "compare", c.controller, {}});
    controllers.push_back(c.controller);
  }
  const std::string name = display_name(job.controller.type);
  r.comparison.push_back({name + " (job)", "baseline", job.controller, {}});
  controllers.push_back(job.controller);
  r.comparison.push_back({"optimal " + name, "tuned", r.tuned_controller, {}});
  controllers.push_back(r.tuned_controller);

  const auto every = std::max<std::int64_t>(
      1, std::llround(kComparisonRecordInterval / job.scenarios.front().sample_time));
  const std::vector<CandidateOutcome> outcomes = evaluator.evaluate_controllers(controllers, every);
  for (std::size_t i = 0; i < outcomes.size(); ++i) r.comparison[i].outcome = outcomes[i];
  r.simulations = evaluator.simulations();
  return r;
}

json gains_document(const TuningOutcome& r) {
  const Job& job = r.job;
  const json job_json = to_json(job);
  json g;
  g["schema"] = kGainsSchema;
  g["controller"] = to_json(r.tuned_controller);
  g["tuned"] = json::object();
  for (const auto& [name, value] : r.tuned) g["tuned"][name] = value;
  g["sample_time"] = job.scenarios.front().sample_time;
  g["plant"] = to_json(job.plant);
  json objective = to_json(job.objective);
  objective["value"] = json_number(r.best().outcome.evaluation.objective);
  g["objective"] = objective;
  g["fitness"] = json_number(r.optimization.best_fitness);
  const ComparedController& base = r.baseline();
  g["baseline"] = {{"controller", to_json(base.controller)},
                   {"objective", json_number(base.outcome.evaluation.objective)},
                   {"fitness", json_number(base.outcome.evaluation.fitness)}};
  json optimizer = job_json["tuning"]["algorithm"];
  optimizer["seed"] = r.seed;
  optimizer["evaluations"] = r.optimization.evaluations;
  optimizer["completed"] = r.optimization.completed;
  g["optimizer"] = optimizer;
  std::vector<std::string> names;
  for (const auto& t : r.tuned) names.push_back(t.first);
  g["history"] = json::array();
  for (const HistoryRow& h : r.optimization.history)
    g["history"].push_back({{"iteration", h.iteration},
                            {"best_fitness", json_number(h.best_fitness)},
                            {"best", named(names, h.best)},
                            {"mean_loudness", json_number(h.mean_loudness)},
                            {"mean_pulse_rate", json_number(h.mean_pulse_rate)},
                            {"evaluations", h.evaluations}});
  g["job"] = {{"name", job.name}, {"sha256", r.job_sha256}};
  g["generator"] = {{"name", kToolName}, {"version", kVersion}};
  return g;
}

std::string history_csv(const TuningOutcome& r) {
  std::string s = "iteration,best_fitness";
  for (const auto& t : r.tuned) s += "," + t.first;
  s += ",mean_loudness,mean_pulse_rate,evaluations\n";
  char buf[48];
  const auto cell = [&](double v) {
    if (std::isnan(v)) return std::string(",");
    std::snprintf(buf, sizeof buf, ",%.17g", v);
    return std::string(buf);
  };
  for (const HistoryRow& h : r.optimization.history) {
    s += std::to_string(h.iteration) + cell(h.best_fitness);
    for (double v : h.best) s += cell(v);
    s += cell(h.mean_loudness) + cell(h.mean_pulse_rate) + "," + std::to_string(h.evaluations) +
         "\n";
  }
  return s;
}

json comparison_document(const TuningOutcome& r) {
  json doc;
  doc["job"] = r.job.name;
  doc["objective"] = to_json(r.job.objective);
  doc["scenarios"] = json::array();
  for (const sim::Scenario& s : r.job.scenarios) doc["scenarios"].push_back(s.name);
  doc["controllers"] = json::array();
  for (const ComparedController& c : r.comparison) {
    json cj;
    cj["label"] = c.label;
    cj["role"] = c.role;
    cj["controller"] = to_json(c.controller);
    cj["objective"] = json_number(c.outcome.evaluation.objective);
    cj["fitness"] = json_number(c.outcome.evaluation.fitness);
    if (!c.outcome.error.empty()) cj["error"] = c.outcome.error;
    cj["scenarios"] = json::array();
    for (std::size_t i = 0; i < c.outcome.evaluation.scenarios.size(); ++i) {
      json m = metrics_json(c.outcome.evaluation.scenarios[i]);
      m["name"] = r.job.scenarios[i].name;
      if (i < c.outcome.trajectories.size())
        m["trajectory"] = trajectory_file(r, static_cast<std::size_t>(&c - r.comparison.data()), i);
      cj["scenarios"].push_back(m);
    }
    doc["controllers"].push_back(cj);
  }
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
  o << "Objective: " << sim::to_string(job.objective.metric) << " over ["
    << detail::format_number(job.objective.window.t0) << ", "
    << (std::isfinite(job.objective.window.t1) ? detail::format_number(job.objective.window.t1)
                                               : std::string("end"))
    << ") s, " << to_string(job.objective.aggregate) << " over scenarios.\n";
  for (std::size_t s = 0; s < job.scenarios.size(); ++s) {
    const sim::Scenario& sc = job.scenarios[s];
    o << "\n## Scenario " << sc.name << "\n\n";
    const sim::Metrics& first = r.comparison.front().outcome.evaluation.scenarios.at(s);
    o << "| controller | ISE | IAE | ITAE | max \\|u_d\\| | control TV |";
    for (const sim::Window& w : first.extra_windows)
      o << " ISE [" << detail::format_number(w.t0) << ", " << detail::format_number(w.t1) << ") |";
    for (std::size_t f = 0; f < first.fault_onsets.size(); ++f)
      o << " peak ‖e‖ after fault " << f + 1 << " |";
    o << "\n|---|---:|---:|---:|---:|---:|";
    for (std::size_t k = 0; k < first.extra_windows.size() + first.fault_onsets.size(); ++k)
      o << "---:|";
    o << "\n";
    for (const ComparedController& c : r.comparison) {
      const sim::Metrics& m = c.outcome.evaluation.scenarios.at(s);
      o << "| " << c.label << (m.diverged ? " (diverged)" : "") << " | "
        << detail::format_number(m.errors.ise) << " | " << detail::format_number(m.errors.iae)
        << " | " << detail::format_number(m.errors.itae) << " | "
        << detail::format_number(m.max_abs_u) << " | " << detail::format_number(m.control_tv)
        << " |";
      for (const sim::ErrorIntegrals& e : m.extra) o << " " << detail::format_number(e.ise) << " |";
      for (double p : m.peak_error_after_fault) o << " " << detail::format_number(p) << " |";
      o << "\n";
    }
  }
  o << "\nISE in rad²·s, IAE in rad·s, ITAE in rad·s², peak errors in rad; control TV = Σ‖u_k − "
       "u_{k−1}‖ "
       "(chattering).\n";
  return o.str();
}

std::map<std::string, std::string> output_files(const TuningOutcome& r) {
  std::map<std::string, std::string> files = {
      {"gains.json", gains_document(r).dump(2) + "\n"},
      {"history.csv", history_csv(r)},
      {"job.json", to_json(r.job).dump(2) + "\n"},
      {"comparison.json", comparison_document(r).dump(2) + "\n"},
      {"comparison.md", comparison_markdown(r)}};
  for (std::size_t c = 0; c < r.comparison.size(); ++c)
    for (std::size_t s = 0; s < r.comparison[c].outcome.trajectories.size(); ++s)
      files[trajectory_file(r, c, s)] = trajectory_csv(r.comparison[c].outcome.trajectories[s]);
  return files;
}

json run_metadata(const TuningOutcome& r, double wall_seconds) {
  rusage ru{};
  const long max_rss_kib = ::getrusage(RUSAGE_SELF, &ru) == 0 ? ru.ru_maxrss : -1;
  return {{"threads", r.threads},
          {"wall_seconds", wall_seconds},
          {"simulations", r.simulations},
          {"max_rss_kib", max_rss_kib},
          {"seed", r.seed},
          {"generator", {{"name", kToolName}, {"version", kVersion}}}};
}

void write_outputs(const TuningOutcome& r, const std::filesystem::path& dir) {
  for (const auto& [name, content] : output_files(r)) write_file_atomic(dir / name, content);
}

}  // namespace ftc::tune
