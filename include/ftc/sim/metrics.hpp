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

// MetricsAccumulator (sim_core/metrics_accumulator.hpp) accumulates them sample by sample, with
// the per-metric accumulators the batch kernel runs in its lanes (sim_core/lanes/metric_lanes.hpp).

}  // namespace ftc::sim
