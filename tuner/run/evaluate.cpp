#include "ftc/tune/run/evaluate.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <numeric>
#include <sstream>

#include "ftc/runtime/controller_json.hpp"
#include "ftc/runtime/gains.hpp"
#include "ftc/sim/input_error.hpp"
#include "ftc/tune/io/files.hpp"
#include "ftc/tune/job/ensemble.hpp"
#include "ftc/tune/run/documents.hpp"
#include "ftc/tune/run/fault_fields.hpp"
#include "ftc/tune/run/tuning_run.hpp"
#include "io/text.hpp"

namespace ftc::tune {

using nlohmann::json;
namespace fs = std::filesystem;

namespace {

// Members per slice: enough tasks to keep every core busy, few enough that the scenarios and
// metrics of a slice stay small whatever the member count.
constexpr std::int64_t kSlice = 256;

std::vector<double> resolved_values(const sim::PlantSpec& spec) {
  if (!spec.values.empty()) return spec.values;
  const sim::PlantKind* kind = sim::find_plant_kind(spec.model);
  return kind ? kind->defaults() : std::vector<double>{};
}

// A gains file may only be judged on the plant and sample time it was tuned for: a controller
// built from another model's f and G⁺ would be a different controller.
void check_fits(const runtime::Gains& g, const Job& job, const std::string& path) {
  if (g.plant.model != job.plant.model)
    throw InputError(path, "/plant/model",
                     "was tuned for the plant \"" + g.plant.model + "\", the job's is \"" +
                         job.plant.model + "\"");
  if (resolved_values(g.plant) != resolved_values(job.plant))
    throw InputError(path, "/plant",
                     "was tuned for other plant values than the job's (the controller's model "
                     "would not be the job's plant)");
  for (const sim::Scenario& s : job.scenarios) {
    try {
      runtime::check_sample_time(g, s.sample_time);
    } catch (const InputError& e) {
      throw InputError(path, "/sample_time",
                       "was tuned for Ts = " + detail::format_number(g.sample_time, "%.9g") +
                           " s; scenario \"" + s.name + "\" samples at " +
                           detail::format_number(s.sample_time, "%.9g") + " s");
    }
  }
}

MemberResult member_result(const TuningProblem& p, std::size_t i, const sim::Metrics& m) {
  MemberResult r;
  r.scenario = p.scenario(i).name;
  r.recoverable = p.recoverable(i);
  r.objective = p.job().objective.value(m);
  r.metrics = sim::MetricValues::of(m);
  r.diverged = m.diverged;
  for (const GoalConfig& g : p.job().goals) r.goals.push_back(p.goal_value(g, m, i));
  return r;
}

// "a2 stuck abrupt @12.3 s; a4 loss_of_effectiveness incipient @20.1 s", or "none".
std::string faults_summary(const sim::Scenario& s) {
  std::string out;
  for (const sim::Fault& f : s.faults) {
    if (!out.empty()) out += "; ";
    out.append("a")
        .append(std::to_string(f.actuator))
        .append(" ")
        .append(sim::to_string(f.type))
        .append(" ")
        .append(sim::to_string(f.profile.type))
        .append(" @")
        .append(detail::format_number(f.onset, "%.4g"))
        .append(" s");
  }
  return out.empty() ? "none" : out;
}

// A number of evaluation.csv: every digit; a value never reached (NaN) as "nan".
std::string csv_number(double v) {
  return std::isnan(v) ? std::string("nan") : detail::format_number(v, "%.17g");
}

std::string csv_field(const std::string& s) {
  if (s.find_first_of(",\"\n") == std::string::npos) return s;
  std::string o = "\"";
  for (char c : s) o += c == '"' ? std::string("\"\"") : std::string(1, c);
  return o + "\"";
}

// The scenario of member index i (listed scenarios first, then the held-out members).
sim::Scenario scenario_at(const Job& job, std::uint64_t seed, std::int64_t i) {
  const auto listed = static_cast<std::int64_t>(job.scenarios.size());
  if (i < listed) return job.scenarios[static_cast<std::size_t>(i)];
  return ensemble_member(job, seed, i - listed);
}

}  // namespace

EvaluationResult evaluate_out_of_sample(const Job& job_in, const EvaluateOptions& options,
                                        BatchEvaluator& evaluator) {
  EvaluationResult r;
  r.job = job_in;
  Job& job = r.job;
  throw_if_errors("job " + job.name, job.validate());
  if (!job.ensemble && (options.seed || options.count))
    throw InputError(options.seed ? "--seed" : "--count", "",
                     "the job \"" + job.name + "\" has no ensemble to draw members from");
  if (job.ensemble) {
    r.seed = options.seed.value_or(job.ensemble->seed + 1);
    r.count = ensemble_count(job, options.count);
  }

  // The controllers: the compare list, the job's own, then every gains file.
  for (const CompareEntry& c : job.compare)
    r.controllers.push_back({c.label, "compare", c.controller, {}, {}, {}, 0.0});
  r.controllers.push_back(
      {display_name(job.controller.type) + " (job)", "job", job.controller, {}, {}, {}, 0.0});
  for (const EvaluateOptions::GainsFile& f : options.gains) {
    const runtime::Gains g = runtime::read_gains(f.path);
    check_fits(g, job, f.path.string());
    r.controllers.push_back({f.label.empty() ? f.path.string() : f.label,
                             f.path.string(),
                             g.controller,
                             {},
                             {},
                             {},
                             0.0});
  }
  for (const auto& [label, controller] : options.controllers)
    r.controllers.push_back({label, "front", controller, {}, {}, {}, 0.0});
  for (std::size_t i = 0; i < r.controllers.size(); ++i)
    for (std::size_t j = 0; j < i; ++j)
      if (r.controllers[i].label == r.controllers[j].label)
        throw InputError("--gains", "",
                         "two controllers are labelled \"" + r.controllers[i].label +
                             "\"; give one a label of its own (--gains LABEL=FILE)");
  std::vector<sim::ControllerConfig> controllers;
  for (const EvaluatedController& c : r.controllers) controllers.push_back(c.controller);

  // Slice by slice: build the slice's scenarios on this thread, simulate every (controller,
  // scenario) pair through the evaluator, keep a few numbers per member.
  const auto listed = static_cast<std::int64_t>(job.scenarios.size());
  const std::int64_t total = listed + r.count;
  std::vector<std::vector<double>> counted(r.controllers.size());
  // Per controller and goal, the counted members' values of the goal's metric.
  std::vector<std::vector<std::vector<double>>> goal_values(
      r.controllers.size(), std::vector<std::vector<double>>(job.goals.size()));
  std::vector<int> diverged(r.controllers.size(), 0);
  int unrecoverable = 0;
  for (EvaluatedController& c : r.controllers) c.members.reserve(static_cast<std::size_t>(total));
  for (std::int64_t begin = 0; begin < total; begin += kSlice) {
    const std::int64_t end = std::min(total, begin + kSlice);
    std::vector<sim::Scenario> slice;
    slice.reserve(static_cast<std::size_t>(end - begin));
    for (std::int64_t i = begin; i < end; ++i) slice.push_back(scenario_at(job, r.seed, i));
    const auto slice_listed =
        static_cast<std::size_t>(std::clamp(listed - begin, std::int64_t{0}, end - begin));
    const TuningProblem problem(job, std::move(slice), slice_listed);
    const std::vector<CandidateOutcome> outcomes = problem.evaluate(controllers, evaluator);
    for (std::size_t i = 0; i < problem.scenarios(); ++i)
      unrecoverable += problem.recoverable(i) ? 0 : 1;
    for (std::size_t c = 0; c < outcomes.size(); ++c) {
      if (!outcomes[c].error.empty())
        throw InputError("controller \"" + r.controllers[c].label + "\"", "", outcomes[c].error);
      const std::vector<sim::Metrics>& per = outcomes[c].evaluation.scenarios;
      for (std::size_t i = 0; i < per.size(); ++i) {
        r.controllers[c].members.push_back(member_result(problem, i, per[i]));
        if (!problem.counted(i)) continue;  // listed, but outside the aggregates
        diverged[c] += per[i].diverged ? 1 : 0;
        counted[c].push_back(r.controllers[c].members.back().objective);
        for (std::size_t k = 0; k < job.goals.size(); ++k)
          goal_values[c][k].push_back(r.controllers[c].members.back().goals[k]);
      }
    }
    r.simulations += static_cast<std::int64_t>(controllers.size() * problem.scenarios());
    if (options.progress) options.progress(end, total);
  }
  for (std::size_t c = 0; c < r.controllers.size(); ++c) {
    Summary& s = r.controllers[c].aggregates;
    s = summarize_values(job.objective, std::move(counted[c]));
    s.scenarios = static_cast<int>(total);
    s.unrecoverable = unrecoverable;
    s.diverged = diverged[c];
    EvaluatedController& ec = r.controllers[c];
    for (std::size_t k = 0; k < job.goals.size(); ++k) {
      ec.goals.push_back(aggregate_goal(job.goals[k], std::move(goal_values[c][k])));
      ec.violation += job.goals[k].violation(ec.goals.back());
    }
  }
  return r;
}

namespace {

// Collects small pieces and hands them to the sink 64 KiB at a time.
class Buffered {
 public:
  explicit Buffered(const ChunkSink& sink) : sink_(sink) {}
  ~Buffered() = default;
  Buffered& operator<<(std::string_view s) {
    buf_.append(s);
    if (buf_.size() >= (1u << 16)) flush();
    return *this;
  }
  void flush() {
    sink_(buf_);
    buf_.clear();
  }

 private:
  const ChunkSink& sink_;
  std::string buf_;
};

json header_document(const EvaluationResult& r) {
  const Job& job = r.job;
  json doc;
  doc["schema"] = kEvaluationSchema;
  doc["job"] = job.name;
  doc["seed"] = r.seed;
  doc["count"] = r.count;
  doc["listed"] = job.scenarios.size();
  // The objective in the job's own form.
  const json objective = to_json(job.objective);
  for (const char* k : {"metric", "window", "window_from", "aggregate", "q", "alpha"})
    if (objective.contains(k)) doc[k] = objective[k];
  doc["unrecoverable"] =
      job.ensemble && job.ensemble->unrecoverable == Unrecoverable::include ? "include" : "exclude";
  return doc;
}

}  // namespace

void write_evaluation_json(const EvaluationResult& r, const ChunkSink& sink) {
  // Written member by member: the document of a million members is never built in memory.
  Buffered out(sink);
  std::string head = header_document(r).dump(2);
  head.pop_back();  // the closing brace: the controllers follow
  while (!head.empty() && head.back() == '\n') head.pop_back();
  out << head << ",\n  \"controllers\": [";
  for (std::size_t c = 0; c < r.controllers.size(); ++c) {
    const EvaluatedController& ec = r.controllers[c];
    json meta = {{"label", ec.label},
                 {"source", ec.source},
                 {"controller", to_json(ec.controller)},
                 {"aggregates", summary_json(ec.aggregates)}};
    if (!r.job.goals.empty()) meta["goals"] = goals_json(r.job, ec.goals, ec.violation);
    std::string m = meta.dump();
    m.pop_back();
    out << (c ? ",\n    " : "\n    ") << m << ", \"members\": [";
    for (std::size_t i = 0; i < ec.members.size(); ++i) {
      const MemberResult& x = ec.members[i];
      json row = {{"scenario", x.scenario},
                  {"recoverable", x.recoverable},
                  {"objective", json_number(x.objective)},
                  {"diverged", x.diverged}};
      if (!x.goals.empty()) {
        row["goals"] = json::array();
        for (double v : x.goals) row["goals"].push_back(json_number(v));
      }
      // Every field of the record under its name (metrics_json's form): a fault field as an
      // array, one value per fault onset.
      for (std::size_t f = 0; f < sim::kMetricFieldCount; ++f) {
        const std::span<const double> v = x.metrics.field(f);
        const std::string name(sim::kMetricFields[f].name);
        if (sim::kMetricFields[f].scope != sim::MetricScope::fault) {
          row[name] = json_number(v[0]);
          continue;
        }
        row[name] = json::array();
        for (double p : v) row[name].push_back(json_number(p));
      }
      // With the member's faults as fields (drawn again rather than kept: flat memory).
      row["faults"] = fault_fields(scenario_at(r.job, r.seed, static_cast<std::int64_t>(i)).faults);
      out << (i ? ",\n      " : "\n      ") << row.dump();
    }
    out << "\n    ]}";
  }
  out << "\n  ]\n}\n";
  out.flush();
}

void write_evaluation_csv(const EvaluationResult& r, const ChunkSink& sink) {
  Buffered out(sink);
  // The faults in words, then as fields (fault<k>_actuator, _kind, ...: fault_fields.hpp), then
  // the record's fields in table order; a fault field's cell holds one value per fault onset,
  // separated by ';' (empty without faults).
  const std::size_t faults_n = max_faults(r.job);
  out << "controller,scenario,faults" << fault_columns_header(faults_n) << ",recoverable,objective";
  for (const sim::MetricField& f : sim::kMetricFields) out << "," << f.name;
  out << ",diverged";
  // A job with goals: each goal's metric in its own window, named as trials.csv names them.
  for (std::size_t k = 0; k < r.job.goals.size(); ++k)
    out << ",goal" << std::to_string(k) << "_" << r.job.goals[k].metric->name;
  out << "\n";
  for (const EvaluatedController& c : r.controllers) {
    const std::string label = csv_field(c.label);
    for (std::size_t i = 0; i < c.members.size(); ++i) {
      const MemberResult& m = c.members[i];
      // Members are drawn again rather than kept: memory stays flat in the member count.
      const sim::Scenario scenario = scenario_at(r.job, r.seed, static_cast<std::int64_t>(i));
      const std::string faults = csv_field(faults_summary(scenario));
      out << label << "," << csv_field(m.scenario) << "," << faults
          << fault_columns(scenario.faults, faults_n) << "," << (m.recoverable ? "1," : "0,")
          << csv_number(m.objective);
      for (std::size_t f = 0; f < sim::kMetricFieldCount; ++f) {
        const std::span<const double> v = m.metrics.field(f);
        out << ",";
        for (std::size_t k = 0; k < v.size(); ++k) out << (k ? ";" : "") << csv_number(v[k]);
      }
      out << (m.diverged ? ",1" : ",0");
      for (double v : m.goals) out << "," << csv_number(v);
      out << "\n";
    }
  }
  out.flush();
}

std::string evaluation_table(const EvaluationResult& r) {
  std::size_t w = std::string("controller").size();
  for (const EvaluatedController& c : r.controllers) w = std::max(w, c.label.size());
  std::ostringstream o;
  char buf[512];
  std::snprintf(buf, sizeof buf, "  %-*s %11s %11s %11s %11s %11s %8s\n", static_cast<int>(w),
                "controller", "mean", "median", "p90", "max", "CVaR", "diverged");
  o << buf;
  for (const EvaluatedController& c : r.controllers) {
    const Summary& s = c.aggregates;
    const auto f = [](double v) { return detail::format_number(v, "%.5g"); };
    std::snprintf(buf, sizeof buf, "  %-*s %11s %11s %11s %11s %11s %8d\n", static_cast<int>(w),
                  c.label.c_str(), f(s.mean).c_str(), f(s.median).c_str(), f(s.p90).c_str(),
                  f(s.max).c_str(), f(s.cvar).c_str(), s.diverged);
    o << buf;
  }
  if (r.job.goals.empty()) return o.str();
  o << "\n  goals, aggregated over the members as the job aggregates them:\n";
  for (std::size_t k = 0; k < r.job.goals.size(); ++k)
    o << "    goal" << k << ": "
      << goal_label(r.job, k, r.job.scenarios.size() + static_cast<std::size_t>(r.count)) << "\n";
  std::snprintf(buf, sizeof buf, "  %-*s", static_cast<int>(w), "controller");
  o << buf;
  for (std::size_t k = 0; k < r.job.goals.size(); ++k) {
    std::snprintf(buf, sizeof buf, " %11s", ("goal" + std::to_string(k)).c_str());
    o << buf;
  }
  o << "  feasible\n";
  for (const EvaluatedController& c : r.controllers) {
    std::snprintf(buf, sizeof buf, "  %-*s", static_cast<int>(w), c.label.c_str());
    o << buf;
    for (double v : c.goals) {
      std::snprintf(buf, sizeof buf, " %11s", detail::format_number(v, "%.5g").c_str());
      o << buf;
    }
    o << (c.violation > 0 ? "  no\n" : "  yes\n");
  }
  return o.str();
}

std::vector<std::size_t> worst_members(const EvaluatedController& c, std::size_t k) {
  std::vector<std::size_t> idx;
  for (std::size_t i = 0; i < c.members.size(); ++i)
    if (c.members[i].recoverable) idx.push_back(i);
  // Worst first; ties (two diverged members) in scenario order, so the choice is reproducible.
  std::stable_sort(idx.begin(), idx.end(), [&](std::size_t a, std::size_t b) {
    return c.members[a].objective > c.members[b].objective;
  });
  if (idx.size() > k) idx.resize(k);
  return idx;
}

std::string controller_slug(const EvaluationResult& r, std::size_t c) {
  char index[24];
  std::snprintf(index, sizeof index, "%02zu-", c + 1);
  const std::string slug = label_slug(r.controllers.at(c).label);
  return index + (slug.empty() ? std::string("controller") : slug);
}

void write_evaluation(const EvaluationResult& r, const fs::path& dir) {
  write_file_atomic(dir / "evaluation.json",
                    [&](const ChunkSink& sink) { write_evaluation_json(r, sink); });
  write_file_atomic(dir / "evaluation.csv",
                    [&](const ChunkSink& sink) { write_evaluation_csv(r, sink); });
  // Each worst member as a complete job: the controller that did badly on the one scenario, so
  // `ftctune simulate worst/<controller>/<rank>-<scenario>.json` replays it and draws it.
  fs::remove_all(dir / "worst");
  for (std::size_t c = 0; c < r.controllers.size(); ++c) {
    const EvaluatedController& ec = r.controllers[c];
    int rank = 0;
    for (std::size_t i : worst_members(ec, kWorstMembers)) {
      Job one = r.job;
      one.name = r.job.name + "-" + ec.members[i].scenario;
      one.ensemble = nullptr;
      one.compare.clear();
      one.tuning.reset();
      one.controller = ec.controller;
      one.scenarios = {scenario_at(r.job, r.seed, static_cast<std::int64_t>(i))};
      const fs::path file = dir / "worst" / controller_slug(r, c) /
                            (std::to_string(++rank) + "-" + ec.members[i].scenario + ".json");
      write_file_atomic(file, to_json(one).dump(2) + "\n");
    }
  }
}

}  // namespace ftc::tune
