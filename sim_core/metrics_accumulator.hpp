#pragma once
// MetricsAccumulator: the Metrics of one run (ftc/sim/metrics.hpp, SPEC §6) accumulated sample
// by sample without storing the trajectory. Each metric's operations are those of
// lanes/metric_lanes.hpp with one lane (T = double, bool masks), the functions the batch kernel
// (lanes/closed_loop.hpp) calls on its lanes: the two cannot drift apart.
#include <cstddef>
#include <limits>
#include <utility>
#include <vector>

#include "ftc/sim/metrics.hpp"
#include "ftc/sim/types.hpp"
#include "lanes/metric_lanes.hpp"

namespace ftc::sim {

// For a plant with N axes and M actuators. All storage is sized at construction; sample()
// never allocates.
template <int N, int M>
class MetricsAccumulator {
 public:
  MetricsAccumulator(double sample_time, Window window, std::vector<Window> extra_windows,
                     std::vector<double> fault_onsets)
      : Ts_(sample_time) {
    m_.window = window;
    m_.extra.assign(extra_windows.size(), ErrorIntegrals{});
    m_.extra_windows = std::move(extra_windows);
    m_.peak_error_after_fault.assign(fault_onsets.size(), std::numeric_limits<double>::quiet_NaN());
    m_.fault_onsets = std::move(fault_onsets);
  }

  // The sample at t = k Ts (k = 0, 1, ...): X(t) and the command u_d(t).
  void sample(double t, const StateOf<N>& x, const Vec<M>& u_d) {
    const lane::ErrorNorms<double> e = lane::error_norms<N, double>(x);
    const lane::ErrorTerms<double> terms = lane::error_terms(Ts_, Ts_ * t, e);
    const auto add = [&](const Window& w, ErrorIntegrals& acc) {
      lane::add_error_terms<double>(lane::in_window(t, w.t0, w.t1), terms, acc.ise, acc.iae,
                                    acc.itae);
    };
    add(m_.window, m_.errors);
    for (std::size_t i = 0; i < m_.extra.size(); ++i) add(m_.extra_windows[i], m_.extra[i]);
    lane::add_max_abs_u<M, double>(true, u_d, m_.max_abs_u);
    if (has_prev_) lane::add_control_tv<M, double>(true, u_d, u_prev_, m_.control_tv);
    u_prev_ = u_d;
    has_prev_ = true;
    if (m_.fault_onsets.empty()) return;
    const double en = lane::sqrt(e.sq);
    for (std::size_t i = 0; i < m_.fault_onsets.size(); ++i)
      lane::add_peak<double>(t >= m_.fault_onsets[i], en, m_.peak_error_after_fault[i]);
  }

  void mark_diverged(double t) { m_.mark_diverged(t); }
  const Metrics& result() const { return m_; }

 private:
  double Ts_;
  Metrics m_;
  Vec<M> u_prev_ = Vec<M>::Zero();
  bool has_prev_ = false;
};

}  // namespace ftc::sim
