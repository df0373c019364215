#pragma once
// The metrics record (Metrics, ftc/sim/metrics.hpp) described once: one entry per metric with
// its name (the JSON key), its unit, its column label, how it combines over scenarios, where it
// lives in the record (once per window, once per run, or once per fault onset) and what a job may
// do with it (name it in a goal or as the objective, cap on it, the setting it is measured
// against). Every writer of the record is produced from this table: the MPI wire format below,
// the pack's copy-out (PackFinal's slots, sim_core/lanes/pack.hpp, read back by
// plants/lane_host.hpp), metrics_json, comparison.md's tables and footnote
// (tuner/run/documents.cpp), evaluation.json and evaluation.csv (tuner/run/evaluate.cpp),
// report.html's tables (tuner/report/html.cpp) and `simulate`'s printed table; and so is every
// reader of a metric's name: the job's goals and objective (their names, the JSON Schema's enums,
// the checks of their windows and settings, tuner/job/job.cpp), a goal's value and its capping
// (tuner/problem/problem.cpp), the units of the figures and the service's GET /v1/metrics. A
// metric added to it (with its member in ErrorIntegrals or Metrics and its accumulator in
// sim_core/lanes/metric_lanes.hpp) travels between ranks, lands in every file and, when marked
// `goal`, can be a job's goal, without further code.
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <iterator>
#include <span>
#include <stdexcept>
#include <string>
#include <string_view>
#include <type_traits>
#include <vector>

#include "ftc/sim/metrics.hpp"

namespace ftc::sim {

enum class MetricScope {
  window,  // one value per window: the objective window's in Metrics::errors, the extra ones'
           // in Metrics::extra (ErrorIntegrals' member `in_window`)
  run,     // one value per run (Metrics' member `per_run`)
  fault,   // one value per fault onset, NaN before it is reached (Metrics' member `per_fault`)
};

// How a metric's values over several scenarios (or fault onsets) make one number: the total of
// an integral (ISE over two scenarios is their sum), the largest of a peak or a time, the mean of
// a fraction or an average.
enum class OverScenarios { sum, max, mean };

// The job setting a metric is measured against (MetricSettings; a job's "metrics" block or the
// goal's own key): none, the settling threshold or the steady-state tail.
enum class MetricSetting { none, settling_threshold, steady_state_tail };

struct MetricField {
  std::string_view name;
  std::string_view unit;
  std::string_view label;  // the column of comparison.md (Markdown: '|' escaped)
  MetricScope scope;
  OverScenarios over_scenarios;
  // What the metric is, when its label does not say (comparison.md's and report.html's note).
  std::string_view definition = "";
  // A column of comparison.md's and report.html's tables and `simulate`'s printed table (every
  // field is in the JSON documents and evaluate's files).
  bool in_tables = true;
  // A window field with a column per extra window in comparison.md too (else the objective
  // window's only).
  bool column_per_extra_window = false;
  // A job may name it in a goal (issue 26): minimised or kept at most a limit.
  bool goal = false;
  // It may be the objective: what one soft goal is minimised by, and what trials.csv's objective
  // column holds (a window field).
  bool objective = false;
  // Every run has a value (never NaN; >= 0, +inf when diverged), so the aggregate over the members
  // known so far, the others counted 0, is a lower bound of the aggregate over all: capping may
  // stop a candidate on it (TuningProblem::evaluate_capped). A metric that is NaN on some runs
  // (no sample, no fault, no tail) does not know the count its aggregate will take.
  bool partial_lower_bound = false;
  MetricSetting setting = MetricSetting::none;
  double ErrorIntegrals::*in_window = nullptr;
  double Metrics::*per_run = nullptr;
  std::vector<double> Metrics::*per_fault = nullptr;
};

// In the order of the wire format. ftc/sim/metrics.hpp defines each.
inline constexpr MetricField kMetricFields[] = {
    {.name = "ise",
     .unit = "rad²·s",
     .label = "ISE",
     .scope = MetricScope::window,
     .over_scenarios = OverScenarios::sum,
     .column_per_extra_window = true,
     .goal = true,
     .objective = true,
     .partial_lower_bound = true,
     .in_window = &ErrorIntegrals::ise},
    {.name = "iae",
     .unit = "rad·s",
     .label = "IAE",
     .scope = MetricScope::window,
     .over_scenarios = OverScenarios::sum,
     .goal = true,
     .objective = true,
     .partial_lower_bound = true,
     .in_window = &ErrorIntegrals::iae},
    {.name = "itae",
     .unit = "rad·s²",
     .label = "ITAE",
     .scope = MetricScope::window,
     .over_scenarios = OverScenarios::sum,
     .goal = true,
     .objective = true,
     .partial_lower_bound = true,
     .in_window = &ErrorIntegrals::itae},
    {.name = "max_abs_u",
     .unit = "the command's unit",
     .label = "max \\|u_d\\|",
     .scope = MetricScope::run,
     .over_scenarios = OverScenarios::max,
     .per_run = &Metrics::max_abs_u},
    {.name = "control_tv",
     .unit = "the command's unit",
     .label = "control TV",
     .scope = MetricScope::run,
     .over_scenarios = OverScenarios::sum,
     .definition = "Σ‖u_k − u_{k−1}‖ (chattering)",
     .goal = true,
     .partial_lower_bound = true,
     .per_run = &Metrics::control_tv},
    {.name = "peak_error_after_fault",
     .unit = "rad",
     .label = "peak ‖e‖ after fault",
     .scope = MetricScope::fault,
     .over_scenarios = OverScenarios::max,
     .goal = true,
     .per_fault = &Metrics::peak_error_after_fault},
    {.name = "control_energy",
     .unit = "the command's unit²·s",
     .label = "control energy",
     .scope = MetricScope::window,
     .over_scenarios = OverScenarios::sum,
     .definition = "Σ Ts ‖u_d‖²",
     .in_tables = false,
     .goal = true,
     .partial_lower_bound = true,
     .in_window = &ErrorIntegrals::control_energy},
    {.name = "peak_command",
     .unit = "the command's unit",
     .label = "peak command",
     .scope = MetricScope::window,
     .over_scenarios = OverScenarios::max,
     .definition = "max |u_d,j| in the window",
     .in_tables = false,
     .goal = true,
     .partial_lower_bound = true,
     .in_window = &ErrorIntegrals::peak_command},
    {.name = "saturation_fraction",
     .unit = "1",
     .label = "saturation fraction",
     .scope = MetricScope::window,
     .over_scenarios = OverScenarios::mean,
     .definition = "the share of samples with a command at or beyond its limit",
     .in_tables = false,
     .goal = true,
     .in_window = &ErrorIntegrals::saturation_fraction},
    {.name = "settling_time",
     .unit = "s",
     .label = "settling time",
     .scope = MetricScope::window,
     .over_scenarios = OverScenarios::max,
     .definition = "from the first fault until ‖e‖ stays below the job's threshold",
     .in_tables = false,
     .goal = true,
     .setting = MetricSetting::settling_threshold,
     .in_window = &ErrorIntegrals::settling_time},
    {.name = "steady_state_error",
     .unit = "rad",
     .label = "steady-state error",
     .scope = MetricScope::window,
     .over_scenarios = OverScenarios::mean,
     .definition = "the mean ‖e‖ over the window's last tail seconds",
     .in_tables = false,
     .goal = true,
     .setting = MetricSetting::steady_state_tail,
     .in_window = &ErrorIntegrals::steady_state_error},
};
inline constexpr std::size_t kMetricFieldCount = std::size(kMetricFields);

// The index of the field named `name` in kMetricFields: compile-time only (a name the table does
// not have is a compile error), for the few places that need one field by name, such as the
// objective's default.
consteval std::size_t metric_index(std::string_view name) {
  for (std::size_t i = 0; i < kMetricFieldCount; ++i)
    if (kMetricFields[i].name == name) return i;
  throw std::logic_error("no such metric");  // not a constant expression: a compile error
}

// The fields of one scope, and a field's slot among them (its index in PackFinal's arrays of
// that scope): compile-time only, so that a kernel compiled per instruction set emits no code of
// its own for them.
consteval std::size_t metric_count(MetricScope scope) {
  std::size_t n = 0;
  for (const MetricField& f : kMetricFields) n += f.scope == scope ? 1 : 0;
  return n;
}
consteval std::size_t metric_slot(std::string_view name) {
  for (std::size_t i = 0, slot[3] = {0, 0, 0}; i < kMetricFieldCount; ++i) {
    const auto s = static_cast<std::size_t>(kMetricFields[i].scope);
    if (kMetricFields[i].name == name) return slot[s];
    ++slot[s];
  }
  throw std::logic_error("no such metric");  // not a constant expression: a compile error
}

// The field named `name`; throws std::logic_error for a name the table does not have.
inline const MetricField& metric_field(std::string_view name) {
  for (const MetricField& f : kMetricFields)
    if (f.name == name) return f;
  throw std::logic_error("no metric " + std::string(name));
}

// The label without Markdown's escapes (report.html, the terminal).
inline std::string plain_label(const MetricField& f) {
  std::string out;
  for (char c : f.label)
    if (c != '\\') out += c;
  return out;
}

// The note under a table of the record: each tabled field's unit, then the definitions
// ("ISE in rad²·s, …, peak ‖e‖ after fault in rad; control TV = Σ‖u_k − u_{k−1}‖ (chattering).").
// `markdown`: the labels as comparison.md writes them, else plain.
inline std::string units_note(bool markdown) {
  std::string out;
  const auto label = [&](const MetricField& f) {
    return markdown ? std::string(f.label) : plain_label(f);
  };
  for (const MetricField& f : kMetricFields)
    if (f.in_tables)
      out.append(out.empty() ? "" : ", ").append(label(f)).append(" in ").append(f.unit);
  for (const MetricField& f : kMetricFields)
    if (f.in_tables && !f.definition.empty())
      out.append("; ").append(label(f)).append(" = ").append(f.definition);
  return out + ".";
}

// One record's values in its main (objective) window, flat: each field in table order, one value
// for a window or run field, one per fault onset for a fault field. What `evaluate` keeps per
// member, and what its files and `simulate`'s table write.
struct MetricValues {
  std::vector<double> values;
  std::size_t onsets = 0;

  static MetricValues of(const Metrics& m) {
    MetricValues v;
    v.onsets = m.fault_onsets.size();
    for (const MetricField& f : kMetricFields) switch (f.scope) {
        case MetricScope::window:
          v.values.push_back(m.errors.*f.in_window);
          break;
        case MetricScope::run:
          v.values.push_back(m.*f.per_run);
          break;
        case MetricScope::fault:
          for (std::size_t i = 0; i < v.onsets; ++i)
            v.values.push_back(i < (m.*f.per_fault).size() ? (m.*f.per_fault)[i] : NAN);
          break;
      }
    return v;
  }
  // The values of kMetricFields[index]: one, or one per fault onset.
  std::span<const double> field(std::size_t index) const {
    std::size_t at = 0;
    for (std::size_t i = 0; i < index; ++i)
      at += kMetricFields[i].scope == MetricScope::fault ? onsets : 1;
    const std::size_t n = kMetricFields[index].scope == MetricScope::fault ? onsets : 1;
    return std::span<const double>(values).subspan(at, n);
  }
  // The value of the window or run field `name`; throws std::logic_error for another name.
  double get(std::string_view name) const {
    for (std::size_t i = 0; i < kMetricFieldCount; ++i)
      if (kMetricFields[i].name == name && kMetricFields[i].scope != MetricScope::fault)
        return field(i)[0];
    throw std::logic_error("no window or run metric " + std::string(name));
  }
};

// The field's values over scenarios (and, for a fault field, their onsets) as one number, in
// order: the sum, the mean or the largest (for the largest and the mean, values that do not
// exist, NaN, are left out; NaN if none is left).
inline double over_scenarios(const MetricField& f, std::span<const double> values) {
  if (f.over_scenarios == OverScenarios::sum) {
    double s = 0.0;
    for (double v : values) s += v;
    return s;
  }
  if (f.over_scenarios == OverScenarios::mean) {
    double s = 0.0, n = 0.0;
    for (double v : values)
      if (!std::isnan(v)) {
        s += v;
        n += 1.0;
      }
    return n > 0.0 ? s / n : NAN;
  }
  double m = NAN;
  for (double v : values)
    if (!std::isnan(v) && !(m >= v)) m = v;
  return m;
}

// The record's members against the table. The wire format below, the kernel's copy-out and the
// writers move a record field by field of the table, so a member of ErrorIntegrals or Metrics that
// it does not list would silently stay behind (on its rank, in the kernel). These stop compiling
// until a new member has its entry: each entry names one member of its scope's kind, none twice,
// and the structs hold nothing else (Metrics beside its fixed members: the window, the extra
// windows, the onsets, diverged and diverged_at).
namespace record_check {
consteval bool each_entry_names_one_member_of_its_scope() {
  for (std::size_t i = 0; i < kMetricFieldCount; ++i) {
    const MetricField& f = kMetricFields[i];
    const bool w = f.in_window != nullptr, r = f.per_run != nullptr, x = f.per_fault != nullptr;
    if (w + r + x != 1 || w != (f.scope == MetricScope::window) ||
        r != (f.scope == MetricScope::run) || x != (f.scope == MetricScope::fault))
      return false;
    for (std::size_t k = 0; k < i; ++k) {
      const MetricField& g = kMetricFields[k];
      if ((w && g.in_window == f.in_window) || (r && g.per_run == f.per_run) ||
          (x && g.per_fault == f.per_fault))
        return false;
    }
  }
  return true;
}
// Metrics as the table lays it out: its fixed members, a double per run field, a vector per fault
// field.
struct MetricsLayout {
  Window window;
  ErrorIntegrals errors;
  std::vector<Window> extra_windows;
  std::vector<ErrorIntegrals> extra;
  double per_run[metric_count(MetricScope::run)];
  std::vector<double> fault_onsets;
  std::vector<double> per_fault[metric_count(MetricScope::fault)];
  bool diverged;
  double diverged_at;
};
}  // namespace record_check
static_assert(record_check::each_entry_names_one_member_of_its_scope(),
              "a kMetricFields entry names no member of its scope, or one another entry names");
static_assert(sizeof(ErrorIntegrals) == metric_count(MetricScope::window) * sizeof(double),
              "every member of ErrorIntegrals needs its window entry in kMetricFields");
static_assert(sizeof(record_check::MetricsLayout) == sizeof(Metrics),
              "every member of Metrics needs its run or fault entry in kMetricFields");

// The record's wire form (MPI messages: every rank runs the same binary, so doubles travel in
// their memory form): the objective window, its window fields, the extra windows (a count, then
// each), their window fields, the run fields, the fault onsets (a count, then each), each fault
// field's values (a count, then each), diverged, diverged_at.
namespace wire {
template <class T>
void put(std::vector<char>& out, const T& v) {
  static_assert(std::is_trivially_copyable_v<T>);
  const char* p = reinterpret_cast<const char*>(&v);
  out.insert(out.end(), p, p + sizeof(T));
}
template <class T>
T get(const std::vector<char>& in, std::size_t& pos) {
  static_assert(std::is_trivially_copyable_v<T>);
  if (sizeof(T) > in.size() - pos) throw std::runtime_error("malformed MPI message");
  T v;
  std::memcpy(&v, in.data() + pos, sizeof(T));
  pos += sizeof(T);
  return v;
}
inline std::uint64_t get_count(const std::vector<char>& in, std::size_t& pos) {
  const auto n = get<std::uint64_t>(in, pos);
  if (n > in.size()) throw std::runtime_error("malformed MPI message");
  return n;
}
}  // namespace wire

inline void append_metrics_wire(std::vector<char>& out, const Metrics& m) {
  const auto put_windowed = [&](const ErrorIntegrals& e) {
    for (const MetricField& f : kMetricFields)
      if (f.scope == MetricScope::window) wire::put(out, e.*f.in_window);
  };
  wire::put(out, m.window);
  put_windowed(m.errors);
  wire::put<std::uint64_t>(out, m.extra_windows.size());
  for (const Window& w : m.extra_windows) wire::put(out, w);
  wire::put<std::uint64_t>(out, m.extra.size());
  for (const ErrorIntegrals& e : m.extra) put_windowed(e);
  for (const MetricField& f : kMetricFields)
    if (f.scope == MetricScope::run) wire::put(out, m.*f.per_run);
  wire::put<std::uint64_t>(out, m.fault_onsets.size());
  for (double t : m.fault_onsets) wire::put(out, t);
  for (const MetricField& f : kMetricFields) {
    if (f.scope != MetricScope::fault) continue;
    wire::put<std::uint64_t>(out, (m.*f.per_fault).size());
    for (double v : m.*f.per_fault) wire::put(out, v);
  }
  wire::put(out, m.diverged);
  wire::put(out, m.diverged_at);
}

// Reads a record written by append_metrics_wire at `pos` and moves `pos` past it; throws
// std::runtime_error on a short or malformed message.
inline Metrics read_metrics_wire(const std::vector<char>& in, std::size_t& pos) {
  Metrics m;
  const auto get_windowed = [&](ErrorIntegrals& e) {
    for (const MetricField& f : kMetricFields)
      if (f.scope == MetricScope::window) e.*f.in_window = wire::get<double>(in, pos);
  };
  const auto get_doubles = [&](std::vector<double>& v) {
    v.resize(wire::get_count(in, pos));
    for (double& x : v) x = wire::get<double>(in, pos);
  };
  m.window = wire::get<Window>(in, pos);
  get_windowed(m.errors);
  m.extra_windows.resize(wire::get_count(in, pos));
  for (Window& w : m.extra_windows) w = wire::get<Window>(in, pos);
  m.extra.resize(wire::get_count(in, pos));
  for (ErrorIntegrals& e : m.extra) get_windowed(e);
  for (const MetricField& f : kMetricFields)
    if (f.scope == MetricScope::run) m.*f.per_run = wire::get<double>(in, pos);
  get_doubles(m.fault_onsets);
  for (const MetricField& f : kMetricFields)
    if (f.scope == MetricScope::fault) get_doubles(m.*f.per_fault);
  m.diverged = wire::get<bool>(in, pos);
  m.diverged_at = wire::get<double>(in, pos);
  return m;
}

}  // namespace ftc::sim
