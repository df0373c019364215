#pragma once
// Performance metrics of one run (SPEC §6), accumulated sample by sample without storing the
// trajectory. With e_k = X1(t_k) over the samples of a window [t0, t1):
//
//   ise  = Σ Ts ‖e_k‖²     (rad²·s)     iae = Σ Ts Σ_i |e_k,i|     itae = Σ Ts t_k Σ_i |e_k,i|
//
// plus, over the whole run, max |u_d,j|, the control total variation Σ_{k≥1} ‖u_k - u_{k-1}‖₂
// (a chattering measure), and the peak ‖e‖ from each fault onset on. A diverged run has
// ise = iae = itae = +inf in every window.
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "ftc/sim/types.hpp"

namespace ftc::sim {

enum class Metric { ise, iae, itae };
const char* to_string(Metric m);
std::optional<Metric> metric_from_string(std::string_view s);

struct Window {
  double t0 = 0.0;
  double t1 = std::numeric_limits<double>::infinity();
  bool contains(double t) const { return t >= t0 && t < t1; }
};

struct ErrorIntegrals {
  double ise = 0.0;
  double iae = 0.0;
  double itae = 0.0;
  double get(Metric m) const;
};

struct Metrics {
  Window window;                      // the main (objective) window
  ErrorIntegrals errors;              // in `window`
  std::vector<Window> extra_windows;  // further windows asked for
  std::vector<ErrorIntegrals> extra;  // one per extra window
  double max_abs_u = 0.0;             // max_j,k |u_d,j(t_k)|
  double control_tv = 0.0;            // Σ ‖u_k - u_{k-1}‖₂
  std::vector<double> fault_onsets;   // s, in fault order
  std::vector<double>
      peak_error_after_fault;  // max ‖e_k‖ over t_k ≥ onset, rad; NaN if never reached
  bool diverged = false;
  double diverged_at = std::numeric_limits<double>::quiet_NaN();  // s

  double objective(Metric m) const { return errors.get(m); }
  // Marks the run diverged at time t: every error integral becomes +inf.
  void mark_diverged(double t);
};

// Accumulates Metrics on the fly for a plant with N axes and M actuators. All storage is sized
// at construction; sample() never allocates.
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

  // The sums run in index order, spelled out: the batch simulator accumulates the same
  // quantities in SIMD lanes (lanes/closed_loop.hpp) and must get the same bits.
  void sample(double t, const StateOf<N>& x, const Vec<M>& u_d) {
    double e2 = x[0] * x[0], e1 = std::abs(x[0]);
    for (int i = 1; i < N; ++i) {
      e2 = e2 + x[i] * x[i];
      e1 = e1 + std::abs(x[i]);
    }
    if (m_.window.contains(t)) add(m_.errors, t, e2, e1);
    for (std::size_t i = 0; i < m_.extra.size(); ++i)
      if (m_.extra_windows[i].contains(t)) add(m_.extra[i], t, e2, e1);

    double u_max = std::abs(u_d[0]);
    for (int j = 1; j < M; ++j) u_max = u_max < std::abs(u_d[j]) ? std::abs(u_d[j]) : u_max;
    m_.max_abs_u = m_.max_abs_u < u_max ? u_max : m_.max_abs_u;
    if (has_prev_) {
      double d2 = (u_d[0] - u_prev_[0]) * (u_d[0] - u_prev_[0]);
      for (int j = 1; j < M; ++j) d2 = d2 + (u_d[j] - u_prev_[j]) * (u_d[j] - u_prev_[j]);
      m_.control_tv += std::sqrt(d2);
    }
    u_prev_ = u_d;
    has_prev_ = true;

    const double en = std::sqrt(e2);
    for (std::size_t i = 0; i < m_.fault_onsets.size(); ++i)
      if (t >= m_.fault_onsets[i] && !(m_.peak_error_after_fault[i] >= en))
        m_.peak_error_after_fault[i] = en;
  }

  void mark_diverged(double t) { m_.mark_diverged(t); }
  const Metrics& result() const { return m_; }

 private:
  void add(ErrorIntegrals& acc, double t, double e2, double e1) const {
    acc.ise += Ts_ * e2;
    acc.iae += Ts_ * e1;
    acc.itae += (Ts_ * t) * e1;
  }

  double Ts_;
  Metrics m_;
  Vec<M> u_prev_ = Vec<M>::Zero();
  bool has_prev_ = false;
};

}  // namespace ftc::sim
