#pragma once
// Performance metrics of one run (SPEC §6), accumulated sample by sample without storing the
// trajectory. With e_k = X1(t_k) over the samples of a window [t0, t1):
//
//   ise  = Σ Ts ‖e_k‖²     (rad²·s)     iae = Σ Ts Σ_i |e_k,i|     itae = Σ Ts t_k Σ_i |e_k,i|
//
// and, over the same samples, with u_d the command:
//
//   control_energy      = Σ Ts ‖u_d,k‖²            (the command's unit² · s)
//   peak_command        = max_k,j |u_d,k,j|
//   saturation_fraction = (samples with some u_d,k,j at or beyond its limit) / (samples); the
//                         limits are ±u_max, and for a plant with an operating point the
//                         deviation's [lo, hi] within them (NaN: no sample)
//   settling_time       = t_s − t_f: t_f the earliest fault onset, t_s the first sample time
//                         t_k ≥ t_f in the window from which on ‖e‖² < threshold² at every sample
//                         of the window; +inf if the window's last sample is not below; NaN
//                         without a fault, a threshold or a sample after t_f
//   steady_state_error  = the mean ‖e_k‖ over the samples of the window's last `tail` seconds
//                         [min(t1, T) − tail, t1) (T the run's duration; NaN without a tail)
//
// plus, over the whole run, max |u_d,j|, the control total variation Σ_{k≥1} ‖u_k - u_{k-1}‖₂
// (a chattering measure), and the peak ‖e‖ from each fault onset on. A diverged run has every
// window metric +inf in every window (ise = iae = itae = +inf, and the worst value of each
// other).
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

struct Window {
  double t0 = 0.0;
  double t1 = std::numeric_limits<double>::infinity();
  bool contains(double t) const { return t >= t0 && t < t1; }
};

// The metrics of one window (the name is from when they were the error integrals only).
struct ErrorIntegrals {
  double ise = 0.0;
  double iae = 0.0;
  double itae = 0.0;
  double control_energy = 0.0;
  double peak_command = 0.0;
  double saturation_fraction = std::numeric_limits<double>::quiet_NaN();
  double settling_time = std::numeric_limits<double>::quiet_NaN();       // s
  double steady_state_error = std::numeric_limits<double>::quiet_NaN();  // rad
};

// What two window metrics are measured against (SimulationOptions): NaN leaves them NaN.
struct MetricSettings {
  double settling_threshold = std::numeric_limits<double>::quiet_NaN();  // rad, > 0
  double steady_state_tail = std::numeric_limits<double>::quiet_NaN();   // s, > 0
};

// The start of a window's steady-state tail: min(t1, duration) − tail.
inline double tail_start(const Window& w, double duration, double tail) {
  return (w.t1 < duration ? w.t1 : duration) - tail;
}

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

  // Marks the run diverged at time t: every window metric becomes +inf.
  void mark_diverged(double t);
};

// The closed loop accumulates them sample by sample in its lanes (MetricLanes,
// sim_core/lanes/metric_lanes.hpp), and the host reads each lane's record back field by field of
// the metrics record (MetricRows, sim_core/plants/lane_host.hpp; ftc/sim/metrics_record.hpp).

}  // namespace ftc::sim
