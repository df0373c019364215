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

// max_j,k |u_d,j(t_k)|.
template <int M, class T, class U>
FTC_HOT_INLINE void add_max_abs_u(Mask<T> counting, const U& u, T& max_abs_u) {
  T u_max = lane::abs(T(u[0]));
  for (int j = 1; j < M; ++j) {
    const T a_j = lane::abs(T(u[j]));
    u_max = lane::select(u_max < a_j, a_j, u_max);
  }
  max_abs_u = lane::select(counting & (max_abs_u < u_max), u_max, max_abs_u);
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
