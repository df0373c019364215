#pragma once
// The metrics record (Metrics, ftc/sim/metrics.hpp) described once: one entry per metric with
// its name (the JSON key), its unit, and where it lives in the record (once per window, once per
// run, or once per fault onset). The MPI wire format below and metrics_json
// (tuner/run/documents.cpp) are produced from this table, so a metric added to it (with its
// member in Metrics and its accumulator in sim_core/lanes/metric_lanes.hpp) travels between
// ranks and lands in the JSON documents without further code.
#include <cstdint>
#include <cstring>
#include <stdexcept>
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

struct MetricField {
  std::string_view name;
  std::string_view unit;
  std::string_view label;  // the column of comparison.md (Markdown: '|' escaped)
  MetricScope scope;
  // A window field with a column per extra window in comparison.md too (else the objective
  // window's only).
  bool column_per_extra_window = false;
  double ErrorIntegrals::*in_window = nullptr;
  double Metrics::*per_run = nullptr;
  std::vector<double> Metrics::*per_fault = nullptr;
};

// In the order of the wire format and of ErrorIntegrals' members.
inline constexpr MetricField kMetricFields[] = {
    {"ise", "rad²·s", "ISE", MetricScope::window, true, &ErrorIntegrals::ise},
    {"iae", "rad·s", "IAE", MetricScope::window, false, &ErrorIntegrals::iae},
    {"itae", "rad·s²", "ITAE", MetricScope::window, false, &ErrorIntegrals::itae},
    {"max_abs_u", "the command's unit", "max \\|u_d\\|", MetricScope::run, false, nullptr,
     &Metrics::max_abs_u},
    {"control_tv", "the command's unit", "control TV", MetricScope::run, false, nullptr,
     &Metrics::control_tv},
    {"peak_error_after_fault", "rad", "peak ‖e‖ after fault", MetricScope::fault, false, nullptr,
     nullptr, &Metrics::peak_error_after_fault},
};

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
