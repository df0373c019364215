#pragma once
// MetricsAccumulator: the Metrics of one run (ftc/sim/metrics.hpp, SPEC §6) accumulated sample
// by sample without storing the trajectory. Each metric's operations are those of
// lanes/metric_lanes.hpp with one lane (T = double, bool masks), the functions the batch kernel
// (lanes/closed_loop.hpp) calls on its lanes: the two cannot drift apart.
#include <cmath>
#include <cstddef>
#include <optional>
#include <limits>
#include <utility>
#include <vector>

#include "ftc/sim/metrics.hpp"
#include "ftc/sim/types.hpp"
#include "lanes/metric_lanes.hpp"

namespace ftc::sim {

// The limits saturation_fraction measures the command against: ±u_max, and for a plant with an
// operating point the deviation's [lo, hi] within them (lanes/closed_loop.hpp applies both).
struct CommandLimits {
  double lo, hi;
};
inline CommandLimits command_limits(double u_max, double lo, double hi) {
  return {lo > -u_max ? lo : -u_max, hi < u_max ? hi : u_max};
}

// What a run's metrics are measured against besides its windows: the run's duration (the end of
// a window's steady-state tail), the command's limits, the settling threshold and the tail.
template <int M>
struct MetricContext {
  double duration = std::numeric_limits<double>::infinity();
  Vec<M> lo = Vec<M>::Constant(-std::numeric_limits<double>::infinity());
  Vec<M> hi = Vec<M>::Constant(std::numeric_limits<double>::infinity());
  MetricSettings settings;
};

// The earliest of the fault onsets; +inf without a fault (the kernel's unused onsets).
inline double first_onset(const std::vector<double>& onsets) {
  double t = std::numeric_limits<double>::infinity();
  for (double o : onsets) t = o < t ? o : t;
  return t;
}

// For a plant with N axes and M actuators. All storage is sized at construction; sample()
// never allocates.
template <int N, int M>
class MetricsAccumulator {
 public:
  MetricsAccumulator(double sample_time, Window window, std::vector<Window> extra_windows,
                     std::vector<double> fault_onsets, const MetricContext<M>& context = {})
      : Ts_(sample_time), lo_(context.lo), hi_(context.hi) {
    m_.window = window;
    m_.extra.assign(extra_windows.size(), ErrorIntegrals{});
    m_.extra_windows = std::move(extra_windows);
    m_.peak_error_after_fault.assign(fault_onsets.size(), std::numeric_limits<double>::quiet_NaN());
    m_.fault_onsets = std::move(fault_onsets);
    sums_.assign(1 + m_.extra.size(), lane::WindowSums<double>{});
    first_onset_ = first_onset(m_.fault_onsets);
    const MetricSettings& ms = context.settings;
    settling_ = !std::isnan(ms.settling_threshold);
    threshold_sq_ = ms.settling_threshold * ms.settling_threshold;
    tail_ = !std::isnan(ms.steady_state_tail);
    tail_start_.push_back(tail_start(m_.window, context.duration, ms.steady_state_tail));
    for (const Window& w : m_.extra_windows)
      tail_start_.push_back(tail_start(w, context.duration, ms.steady_state_tail));
  }

  // The sample at t = k Ts (k = 0, 1, ...): X(t) and the command u_d(t).
  void sample(double t, const StateOf<N>& x, const Vec<M>& u_d) {
    const lane::ErrorNorms<double> e = lane::error_norms<N, double>(x);
    const lane::ErrorTerms<double> terms = lane::error_terms(Ts_, Ts_ * t, e);
    const lane::CommandNorms<double> c = lane::command_norms<M, double>(u_d);
    const double energy_term = Ts_ * c.sq;
    const bool saturated = lane::at_limit<M, double>(u_d, lo_, hi_);
    const bool above = settling_ && e.sq >= threshold_sq_;
    const bool after_fault = t >= first_onset_;
    const double en = m_.fault_onsets.empty() && !tail_ ? 0.0 : lane::sqrt(e.sq);
    const auto add = [&](const Window& w, ErrorIntegrals& acc, std::size_t i) {
      const bool in = lane::in_window(t, w.t0, w.t1);
      lane::add_error_terms<double>(in, terms, acc.ise, acc.iae, acc.itae);
      lane::add_command<double>(in, energy_term, c.max_abs, saturated, sums_[i]);
      if (settling_) lane::add_settling<double>(in && after_fault, above, t, sums_[i].settled_from);
      if (tail_) lane::add_tail<double>(in && t >= tail_start_[i], en, sums_[i]);
    };
    add(m_.window, m_.errors, 0);
    for (std::size_t i = 0; i < m_.extra.size(); ++i) add(m_.extra_windows[i], m_.extra[i], i + 1);
    lane::add_max<double>(true, c.max_abs, m_.max_abs_u);
    if (has_prev_) lane::add_control_tv<M, double>(true, u_d, u_prev_, m_.control_tv);
    u_prev_ = u_d;
    has_prev_ = true;
    if (m_.fault_onsets.empty()) return;
    for (std::size_t i = 0; i < m_.fault_onsets.size(); ++i)
      lane::add_peak<double>(t >= m_.fault_onsets[i], en, m_.peak_error_after_fault[i]);
  }

  void mark_diverged(double t) { diverged_at_ = t; }

  // The record: each window's sums finished (lanes/metric_lanes.hpp's finish_window), then a
  // diverged run's window metrics +inf.
  Metrics result() const {
    Metrics m = m_;
    const auto finish = [&](ErrorIntegrals& e, const lane::WindowSums<double>& s) {
      const lane::WindowMetrics w = lane::finish_window(s, first_onset_);
      e.control_energy = w.control_energy;
      e.peak_command = w.peak_command;
      e.saturation_fraction = w.saturation_fraction;
      e.settling_time = w.settling_time;
      e.steady_state_error = w.steady_state_error;
    };
    finish(m.errors, sums_[0]);
    for (std::size_t i = 0; i < m.extra.size(); ++i) finish(m.extra[i], sums_[i + 1]);
    if (diverged_at_) m.mark_diverged(*diverged_at_);
    return m;
  }

 private:
  double Ts_;
  Metrics m_;
  Vec<M> lo_, hi_;
  std::vector<lane::WindowSums<double>> sums_;  // the main window's, then each extra window's
  std::vector<double> tail_start_;              // likewise
  double first_onset_ = std::numeric_limits<double>::infinity();
  bool settling_ = false, tail_ = false;
  double threshold_sq_ = 0.0;
  std::optional<double> diverged_at_;
  Vec<M> u_prev_ = Vec<M>::Zero();
  bool has_prev_ = false;
};

}  // namespace ftc::sim
