#pragma once
// The accumulator of each metric of SPEC §6 (ftc/sim/metrics.hpp), written once over the lane
// type: T = double for one run (MetricsAccumulator, sim_core/metrics_accumulator.hpp) or a SIMD
// batch for the W runs of a pack (lanes/closed_loop.hpp). A mask says which lanes count the
// sample (false for a lane that has diverged, or outside a window); with one lane it is a bool.
// Both runs call these functions in the same order, so a lane gets the bits of the one-lane run.
//
// Adding a metric: its accumulator here, called from MetricsAccumulator::sample and from the
// kernel's sample step (stored at its slot of PackFinal), its member in Metrics, its entry in the
// metrics record (ftc/sim/metrics_record.hpp), from which every writer is produced.
#include <limits>

#include "lanes/lane.hpp"

namespace ftc::sim::lane {
inline namespace FTC_ISA_NS {

// ‖e‖² and Σ_i |e_i| of the position error e = X1 (the first N entries of x), summed in index
// order: ((e0 + e1) + e2) + ...
template <class T>
struct ErrorNorms {
  T sq;
  T abs;
};
template <int N, class T, class X>
FTC_HOT_INLINE ErrorNorms<T> error_norms(const X& x) {
  T e2 = x[0] * x[0], e1 = lane::abs(T(x[0]));
  for (int i = 1; i < N; ++i) {
    e2 = e2 + x[i] * x[i];
    e1 = e1 + lane::abs(T(x[i]));
  }
  return {e2, e1};
}

// Whether t is in the window [t0, t1).
template <class T>
FTC_HOT_INLINE Mask<T> in_window(T t, T t0, T t1) {
  return (t >= t0) & (t < t1);
}

// ISE, IAE, ITAE: one sample's terms Ts ‖e‖², Ts Σ|e_i|, (Ts t) Σ|e_i| (Ts_t = Ts · t, formed
// in double before it is broadcast), computed once and added in every window that holds t.
template <class T>
struct ErrorTerms {
  T ise;
  T iae;
  T itae;
};
template <class T>
FTC_HOT_INLINE ErrorTerms<T> error_terms(T Ts, T Ts_t, const ErrorNorms<T>& e) {
  return {Ts * e.sq, Ts * e.abs, Ts_t * e.abs};
}
template <class T>
FTC_HOT_INLINE void add_error_terms(Mask<T> in, const ErrorTerms<T>& d, T& ise, T& iae, T& itae) {
  ise = lane::select(in, ise + d.ise, ise);
  iae = lane::select(in, iae + d.iae, iae);
  itae = lane::select(in, itae + d.itae, itae);
}

// ‖u‖² (summed in index order) and max_j |u_j| of one sample's command, computed once and used
// by every metric of the command.
template <class T>
struct CommandNorms {
  T sq;
  T max_abs;
};
template <int M, class T, class U>
FTC_HOT_INLINE CommandNorms<T> command_norms(const U& u) {
  T sq = T(u[0]) * T(u[0]);
  T u_max = lane::abs(T(u[0]));
  for (int j = 1; j < M; ++j) {
    sq = sq + T(u[j]) * T(u[j]);
    const T a_j = lane::abs(T(u[j]));
    u_max = lane::select(u_max < a_j, a_j, u_max);
  }
  return {sq, u_max};
}

// A running maximum over the samples that count.
template <class T>
FTC_HOT_INLINE void add_max(Mask<T> counting, T v, T& max) {
  max = lane::select(counting & (max < v), v, max);
}

// max_j,k |u_d,j(t_k)|.
template <int M, class T, class U>
FTC_HOT_INLINE void add_max_abs_u(Mask<T> counting, const U& u, T& max_abs_u) {
  add_max<T>(counting, command_norms<M, T>(u).max_abs, max_abs_u);
}

// Whether some u_j is at or beyond its limit: u_j ≤ lo_j or u_j ≥ hi_j.
template <int M, class T, class U, class L>
FTC_HOT_INLINE Mask<T> at_limit(const U& u, const L& lo, const L& hi) {
  Mask<T> m = (T(u[0]) <= lo[0]) | (T(u[0]) >= hi[0]);
  for (int j = 1; j < M; ++j) m = m | (T(u[j]) <= lo[j]) | (T(u[j]) >= hi[j]);
  return m;
}

// The sums behind a window's command, settling and steady-state metrics (ftc/sim/metrics.hpp),
// per window.
template <class T>
struct WindowSums {
  T energy = T(0.0);     // Σ Ts ‖u‖²
  T peak = T(0.0);       // max_j |u_j|
  T saturated = T(0.0);  // samples at a limit
  T samples = T(0.0);    // samples in the window
  T settled_from = T(std::numeric_limits<double>::quiet_NaN());  // see add_settling
  T tail_sum = T(0.0);      // Σ ‖e‖ over the tail
  T tail_samples = T(0.0);  // samples in the tail
};

// One sample in the window (`in`): its energy term Ts ‖u‖², its peak, whether it is at a limit.
template <class T>
FTC_HOT_INLINE void add_command(Mask<T> in, T energy_term, T u_max, Mask<T> saturated,
                                WindowSums<T>& w) {
  w.energy = lane::select(in, w.energy + energy_term, w.energy);
  add_max<T>(in, u_max, w.peak);
  w.saturated = lane::select(in & saturated, w.saturated + T(1.0), w.saturated);
  w.samples = lane::select(in, w.samples + T(1.0), w.samples);
}

// Settling: for a sample in the window at or after the first fault (`in`), settled_from becomes
// +inf while ‖e‖ is at or above the threshold (`above`) and the sample's time t at the first
// sample below it after that (NaN: no such sample yet).
template <class T>
FTC_HOT_INLINE void add_settling(Mask<T> in, Mask<T> above, T t, T& settled_from) {
  const T inf(std::numeric_limits<double>::infinity());
  const T below = lane::select(settled_from < inf, settled_from, t);  // false for NaN too
  settled_from = lane::select(in, lane::select(above, inf, below), settled_from);
}

// A sample in the window's tail (`in`): its ‖e‖.
template <class T>
FTC_HOT_INLINE void add_tail(Mask<T> in, T en, WindowSums<T>& w) {
  w.tail_sum = lane::select(in, w.tail_sum + en, w.tail_sum);
  w.tail_samples = lane::select(in, w.tail_samples + T(1.0), w.tail_samples);
}

// A window's metrics from one lane's sums: the ratios, and the settling time from the first
// fault onset; NaN (the one quiet NaN, whatever the CPU makes of 0/0) where there is no sample.
struct WindowMetrics {
  double control_energy, peak_command, saturation_fraction, settling_time, steady_state_error;
};
inline WindowMetrics finish_window(const WindowSums<double>& w, double first_onset) {
  constexpr double nan = std::numeric_limits<double>::quiet_NaN();
  return {w.energy, w.peak, w.samples > 0.0 ? w.saturated / w.samples : nan,
          w.settled_from == w.settled_from ? w.settled_from - first_onset : nan,
          w.tail_samples > 0.0 ? w.tail_sum / w.tail_samples : nan};
}

// The control total variation: ‖u_k - u_{k-1}‖₂ added for k ≥ 1 (the caller skips k = 0).
template <int M, class T, class U>
FTC_HOT_INLINE void add_control_tv(Mask<T> counting, const U& u, const U& u_prev, T& control_tv) {
  T d2 = (T(u[0]) - T(u_prev[0])) * (T(u[0]) - T(u_prev[0]));
  for (int j = 1; j < M; ++j) d2 = d2 + (T(u[j]) - T(u_prev[j])) * (T(u[j]) - T(u_prev[j]));
  control_tv = lane::select(counting, control_tv + lane::sqrt(d2), control_tv);
}

// The peak ‖e‖ from a fault's onset on (NaN until the onset): `reached` is t ≥ onset for the
// lanes that count, en = sqrt(‖e‖²).
template <class T>
FTC_HOT_INLINE void add_peak(Mask<T> reached, T en, T& peak) {
  peak = lane::select(reached & lane::mask_not(peak >= en), en, peak);
}

}  // namespace FTC_ISA_NS
}  // namespace ftc::sim::lane
