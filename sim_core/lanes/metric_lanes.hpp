#pragma once
// The metrics of SPEC §6 and §16 (ftc/sim/metrics.hpp), accumulated sample by sample in the
// lanes of a pack: each metric's accumulator written once over the lane type (T = double for one
// run, a SIMD batch for W runs), and MetricLanes, the one sequence that calls them for every
// sample and writes each metric's value at its slot of the metrics record. The closed loop
// (lanes/closed_loop.hpp) calls MetricLanes and names no metric. A mask says which lanes count
// the sample (false for a lane that has diverged, or outside a window); with one lane it is a
// bool.
//
// Adding a metric takes three files: its accumulator here (a function below, its sums in
// WindowSums or MetricLanes, its call in MetricLanes::sample and its value in finish_window or
// MetricLanes::write), its member in Metrics or ErrorIntegrals (ftc/sim/metrics.hpp), and its
// entry in the metrics record (ftc/sim/metrics_record.hpp), from which every reader and writer
// of the record, the goals and the dashboard take it.
#include <cstddef>
#include <cstdint>
#include <limits>

#include "ftc/sim/metrics_record.hpp"
#include "lanes/lane.hpp"
#include "lanes/pack.hpp"

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

// The sums behind a window's metrics (ftc/sim/metrics.hpp), per window.
template <class T>
struct WindowSums {
  T ise = T(0.0);                                                // Σ Ts ‖e‖²
  T iae = T(0.0);                                                // Σ Ts Σ_i |e_i|
  T itae = T(0.0);                                               // Σ Ts t Σ_i |e_i|
  T energy = T(0.0);                                             // Σ Ts ‖u‖²
  T peak = T(0.0);                                               // max_j |u_j|
  T saturated = T(0.0);                                          // samples at a limit
  T samples = T(0.0);                                            // samples in the window
  T settled_from = T(std::numeric_limits<double>::quiet_NaN());  // see add_settling
  T tail_sum = T(0.0);                                           // Σ ‖e‖ over the tail
  T tail_samples = T(0.0);                                       // samples in the tail

  // Lane l's sums.
  WindowSums<double> lane(int l) const {
    return {lane::lane_of(ise, l),      lane::lane_of(iae, l),
            lane::lane_of(itae, l),     lane::lane_of(energy, l),
            lane::lane_of(peak, l),     lane::lane_of(saturated, l),
            lane::lane_of(samples, l),  lane::lane_of(settled_from, l),
            lane::lane_of(tail_sum, l), lane::lane_of(tail_samples, l)};
  }
};

// A sample's error terms, in a window that holds it (`in`).
template <class T>
FTC_HOT_INLINE void add_error_terms(Mask<T> in, const ErrorTerms<T>& d, WindowSums<T>& w) {
  w.ise = lane::select(in, w.ise + d.ise, w.ise);
  w.iae = lane::select(in, w.iae + d.iae, w.iae);
  w.itae = lane::select(in, w.itae + d.itae, w.itae);
}

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

// A window's metrics from one lane's sums, each at its slot of the window fields (out[slot ·
// stride]): the sums, the ratios, and the settling time from the first fault onset; NaN (the one
// quiet NaN, whatever the CPU makes of 0/0) where there is no sample.
inline void finish_window(const WindowSums<double>& w, double first_onset, double* out,
                          std::size_t stride) {
  constexpr double nan = std::numeric_limits<double>::quiet_NaN();
  const auto at = [&](std::size_t slot) -> double& { return out[slot * stride]; };
  at(metric_slot("ise")) = w.ise;
  at(metric_slot("iae")) = w.iae;
  at(metric_slot("itae")) = w.itae;
  at(metric_slot("control_energy")) = w.energy;
  at(metric_slot("peak_command")) = w.peak;
  at(metric_slot("saturation_fraction")) = w.samples > 0.0 ? w.saturated / w.samples : nan;
  at(metric_slot("settling_time")) =
      w.settled_from == w.settled_from ? w.settled_from - first_onset : nan;
  at(metric_slot("steady_state_error")) = w.tail_samples > 0.0 ? w.tail_sum / w.tail_samples : nan;
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

namespace ftc::sim::detail {
inline namespace FTC_ISA_NS {

// Every metric of W lanes, from a pack's MetricSetup: the sums of each window and fault onset,
// sized once (no allocation per sample), the samples added one by one in time order, and each
// lane's values written at the end. With T = double it is one run's. Its members are inlined and
// its sums held through plain pointers, never a container whose out-of-line functions take the
// object's address: the loop's compiler then knows that no store of the law or the plant reaches
// the sums, and the reverse (a std::vector here cost the scalar kernels 4 to 7 % in reloads).
template <class T, int N, int M>
class MetricLanes {
  using Mask = lane::Mask<T>;
  static constexpr int W = lane::kWidth<T>;
  static constexpr std::size_t kMaxAbsU = metric_slot("max_abs_u");
  static constexpr std::size_t kControlTv = metric_slot("control_tv");
  static constexpr std::size_t kPeak = metric_slot("peak_error_after_fault");

 public:
  FTC_HOT_INLINE explicit MetricLanes(const MetricSetup<M>& su)
      : windows_(new Window[static_cast<std::size_t>(su.windows)]()),
        onsets_(new Onset[static_cast<std::size_t>(su.onsets)]()),
        n_windows_(su.windows),
        n_onsets_(su.onsets),
        first_onset_(row(su.first_onset)),
        threshold_sq_(row(su.threshold_sq)),
        settling_lane_(threshold_sq_ == threshold_sq_),  // not NaN
        settling_(su.any_settling),
        tail_(su.any_tail),
        need_en_(su.onsets > 0 || su.any_tail) {
    for (int i = 0; i < su.windows; ++i) {
      Window& w = windows_[i];
      w.t0 = row(su.window + (2 * i) * kMaxLanes);
      w.t1 = row(su.window + (2 * i + 1) * kMaxLanes);
      w.tail0 = row(su.tail_start + i * kMaxLanes);
    }
    for (int i = 0; i < su.onsets; ++i) {
      onsets_[i].at = row(su.onset + i * kMaxLanes);
      onsets_[i].peak = T(std::numeric_limits<double>::quiet_NaN());
    }
    for (int j = 0; j < M; ++j) {
      limit_lo_[j] = row(su.limit_lo[j]);
      limit_hi_[j] = row(su.limit_hi[j]);
    }
    for (T& r : run_) r = T(0.0);
  }
  FTC_HOT_INLINE ~MetricLanes() {
    delete[] windows_;
    delete[] onsets_;
  }
  MetricLanes(const MetricLanes&) = delete;
  MetricLanes& operator=(const MetricLanes&) = delete;

  // Sample k at t = k·Ts: the state X(t), the command u_d(t) and the one before it (ignored at
  // k = 0), for the lanes that count.
  template <class X, class U>
  FTC_HOT_INLINE void sample(Mask counting, std::int64_t k, double Ts, const X& x, const U& u,
                             const U& u_prev) {
    const double td = static_cast<double>(k) * Ts;
    const T t(td), Tsv(Ts);
    const lane::ErrorNorms<T> en2 = lane::error_norms<N, T>(x);
    const lane::ErrorTerms<T> terms = lane::error_terms(Tsv, T(Ts * td), en2);
    const lane::CommandNorms<T> cn = lane::command_norms<M, T>(u);
    const T energy_term = Tsv * cn.sq;
    const Mask saturated = lane::at_limit<M, T>(u, limit_lo_, limit_hi_);
    const T en = need_en_ ? lane::sqrt(en2.sq) : T(0.0);
    Mask above = settling_lane_, after_fault = settling_lane_;
    if (settling_) {
      above = en2.sq >= threshold_sq_;
      after_fault = settling_lane_ & (t >= first_onset_);
    }
    for (int i = 0; i < n_windows_; ++i) {
      Window& w = windows_[i];
      const Mask in = counting & lane::in_window(t, w.t0, w.t1);
      lane::add_error_terms<T>(in, terms, w.sums);
      lane::add_command<T>(in, energy_term, cn.max_abs, saturated, w.sums);
      if (settling_) lane::add_settling<T>(in & after_fault, above, t, w.sums.settled_from);
      if (tail_) lane::add_tail<T>(in & (t >= w.tail0), en, w.sums);
    }
    lane::add_max<T>(counting, cn.max_abs, run_[kMaxAbsU]);
    if (k > 0) lane::add_control_tv<M, T>(counting, u, u_prev, run_[kControlTv]);
    for (int i = 0; i < n_onsets_; ++i)
      lane::add_peak<T>(counting & (t >= onsets_[i].at), en, onsets_[i].peak);
  }

  // Lane l's values into `out` (MetricsOut's layout), `first_onset` its earliest fault onset.
  void write(int l, double first_onset, MetricsOut& out) const {
    constexpr std::size_t kWindowFields = MetricsOut::kWindowFields;
    for (int i = 0; i < n_windows_; ++i)
      lane::finish_window(windows_[i].sums.lane(l), first_onset,
                          out.window + static_cast<std::size_t>(i) * kWindowFields * kMaxLanes + l,
                          kMaxLanes);
    for (std::size_t s = 0; s < MetricsOut::kRunFields; ++s)
      out.run[s][l] = lane::lane_of(run_[s], l);
    for (int i = 0; i < n_onsets_; ++i)
      out.fault[(static_cast<std::size_t>(i) * MetricsOut::kFaultFields + kPeak) * kMaxLanes + l] =
          lane::lane_of(onsets_[i].peak, l);
  }

 private:
  static T row(const double* r) { return lane::load_lanes<T>(r); }

  struct Window {
    T t0, t1, tail0;  // [t0, t1), the steady-state tail's start
    lane::WindowSums<T> sums;
  };
  struct Onset {
    T at, peak;  // the onset, the peak ‖e‖ from it on (NaN before)
  };

  Window* windows_;  // n_windows_ of them
  Onset* onsets_;    // n_onsets_ of them
  int n_windows_, n_onsets_;
  T run_[MetricsOut::kRunFields];
  T limit_lo_[M], limit_hi_[M];
  T first_onset_, threshold_sq_;
  Mask settling_lane_;
  bool settling_, tail_, need_en_;
};

}  // namespace FTC_ISA_NS
}  // namespace ftc::sim::detail
