#pragma once
// The closed loop (SPEC §4) for W simulations of one plant in lockstep, one per lane of T, with
// the control law Law (controllers/laws.hpp), written once for every plant. A plant gives its
// dynamics as lane code, PlantLanes<P> (plants/<plant>_lanes.cpp), the way controllers/laws.hpp
// gives the laws: the constants per lane (the PackSetup's truth and model rows, read once) apart
// from what changes (the state X, which the loop owns, and the plant's scratch space, such as
// angle trackers). With T = double it is the scalar simulator: AnyPlant::simulate() and the SIMD
// lanes run this same code, which is why a lane reproduces the scalar run to the last bit.
//
//   per sample k, t = k Ts, for every lane:
//     a_k = f(X) + G(X)·applied(t, u_{k-1}) + Δ(t)   acceleration sensor, before the new command
//     u_k = law(X1, X2, a_k, f_model(X), G⁺_model(X))
//     substeps × RK4 with u_k held; faults and Δ at each stage time
//   with an actuator model (PackSetup::actuator, docs/model.md) the plant is driven by the
//   actuators' output u_a instead of the held command: u_a(t_k) in a_k and at each stage, u_a
//   stepped on the half-step grid towards the command clamped to the actuator's range
//     a lane with |X_i| > 1e6, inf or NaN has diverged: it stops counting, restarts from X(0)
//     with a reset controller (so that it takes no slow paths), and the host ignores it
//   the pack ends when every lane has diverged or all samples are done
//
// PlantLanes<P> gives the plant's shape, static constexpr int N, M, and for the lane type T a
// class Lanes<T> with
//   static constexpr bool kConstantInput;
//   static constexpr bool kTrimmed;   actuators about an operating point (PackSetup::u0, lo, hi)
//   Lanes(const PackSetup<N, M>&)                       the constants of every lane
//   void drift(const V<2N>& x, V<N>& f, V<N>* f_model)  f(X) of the truth (and of the model)
// and, when G depends on X (kConstantInput false; else the loop uses PackSetup::G and G_pinv),
//   void input(const V<M>& u, V<N>& Gu)  G(X) u at the X of the last drift() call, summed
//                                        G(i,0) u0 + G(i,1) u1 + ... in that order
//   void pinv(const V<2N>& x, T* out)    the model's G⁺(X), row-major m×n, as Plant::G_pinv
#include <array>
#include <cstdint>
#include <limits>
#include <type_traits>

#include "controllers/laws.hpp"
#include "ftc/sim/rk4.hpp"
#include "lanes/angle_tracker.hpp"
#include "lanes/elementary.hpp"
#include "lanes/metric_lanes.hpp"
#include "lanes/pack.hpp"

namespace ftc::sim::detail {
inline namespace FTC_ISA_NS {

// The lane code of plant class P: specialised in the plant's lanes file.
template <class P>
struct PlantLanes;

template <class T, class P, template <class, int, int> class Law, bool SharedInputs, int N, int M>
void run_closed_loop(const PackSetup<N, M>& su, PackHost<N, M>& host, PackFinal<N, M>& fin) {
  using Plant = typename PlantLanes<P>::template Lanes<T>;
  static_assert(PlantLanes<P>::N == N && PlantLanes<P>::M == M);
  constexpr int S2 = 2 * N;
  constexpr bool kConstantInput = Plant::kConstantInput;
  constexpr int W = lane::kWidth<T>;
  using Mask = lane::Mask<T>;
  using VN = std::array<T, N>;
  using VM = std::array<T, M>;
  using VS = std::array<T, S2>;
  using Exo = ExoRows<N, M>;
  static_assert(W <= kMaxLanes);

  const ControllerConfig* configs[W];
  for (int l = 0; l < W; ++l) configs[l] = su.configs[l < su.lanes ? l : 0];
  Law<T, N, M> law(configs, su.Ts);

  const auto row = [](const double* r) { return lane::load_lanes<T>(r); };
  // Row r of an instant's exogenous inputs (ExoRows): one value for every lane, or each lane's own.
  constexpr int kStride = Exo::stride(SharedInputs, W);
  constexpr int kInstant = Exo::kCount * kStride;
  const auto input = [](const double* e, int r) FTC_HOT_LAMBDA {
    if constexpr (SharedInputs)
      return T(e[r]);
    else
      return lane::load_lanes<T>(e + r * kStride);
  };
  Plant plant(su);
  const T sat = row(su.saturation);
  constexpr bool kTrimmed = Plant::kTrimmed;
  std::array<T, M> u0, lo_u, hi_u;
  if constexpr (kTrimmed)
    for (int j = 0; j < M; ++j) {
      u0[j] = row(su.u0[j]);
      lo_u[j] = row(su.lo[j]);
      hi_u[j] = row(su.hi[j]);
    }
  VS x0;
  for (int i = 0; i < S2; ++i) x0[i] = row(su.x0[i]);
  T G[N * M];
  if constexpr (kConstantInput)
    for (int i = 0; i < N * M; ++i) G[i] = T(su.G[i]);

  const double Ts = su.Ts;
  const double h = Ts / su.substeps;
  const T hv(h), h2(0.5 * h), h6(h / 6.0);
  const int S = su.substeps;

  // dX2/dt = f(X) + G u + Δ(t), u the command u_d after the faults and saturation at one
  // instant. The applied u (and with a constant G the forcing G u) and Δ depend on the instant
  // and the held command only, so the two midpoint stages share them.
  struct NoGu {};
  struct Forcing {
    [[no_unique_address]] std::conditional_t<kConstantInput, VN, NoGu> Gu;
    VN dist;
    VM u;
  };
  const auto forcing = [&](const double* e, const VM& u_d) FTC_HOT_LAMBDA -> Forcing {
    Forcing F;
    for (int j = 0; j < M; ++j) {
      if constexpr (kTrimmed) {
        // The faults act on the physical output u0 + u_d; then the saturation and the limits.
        const T v =
            (input(e, Exo::kGain + j) * (u0[j] + u_d[j]) + input(e, Exo::kOffset + j)) - u0[j];
        const T lo = lane::select(v < -sat, -sat, v);
        const T s = lane::select(lo > sat, sat, lo);
        const T l = lane::select(s < lo_u[j], lo_u[j], s);
        F.u[j] = lane::select(l > hi_u[j], hi_u[j], l);
      } else {
        const T v = input(e, Exo::kGain + j) * u_d[j] + input(e, Exo::kOffset + j);
        const T lo = lane::select(v < -sat, -sat, v);
        F.u[j] = lane::select(lo > sat, sat, lo);
      }
    }
    for (int i = 0; i < N; ++i) {
      if constexpr (kConstantInput) {
        T g = G[i * M] * F.u[0];
        for (int j = 1; j < M; ++j) g = g + G[i * M + j] * F.u[j];
        F.Gu[i] = g;
      }
      F.dist[i] = input(e, Exo::kDist + i);
    }
    return F;
  };
  // The acceleration at the state of the last drift() call.
  const auto accel = [&](const VN& f, const Forcing& F) FTC_HOT_LAMBDA -> VN {
    VN a;
    if constexpr (kConstantInput) {
      for (int i = 0; i < N; ++i) a[i] = (f[i] + F.Gu[i]) + F.dist[i];
    } else {
      VN Gu;
      plant.input(F.u, Gu);
      for (int i = 0; i < N; ++i) a[i] = (f[i] + Gu[i]) + F.dist[i];
    }
    return a;
  };
  const auto deriv = [&](const VS& x, const Forcing& F) FTC_HOT_LAMBDA -> VS {
    VN f;
    plant.drift(x, f, nullptr);
    const VN a = accel(f, F);
    VS d;
    for (int i = 0; i < N; ++i) {
      d[i] = x[N + i];
      d[N + i] = a[i];
    }
    return d;
  };

  VS x = x0;
  VM u_prev;
  u_prev.fill(T(0.0));
  bool live[W];  // lanes still counting
  for (int l = 0; l < W; ++l) live[l] = l < su.lanes;
  int live_count = su.lanes;
  for (int l = 0; l < W; ++l) {
    fin.samples[l] = su.samples;
    fin.diverged[l] = false;
  }

  // The metrics' sums (lanes/metric_lanes.hpp), per window and fault onset.
  const int nw = su.kernel_metrics ? su.windows : 0, no = su.kernel_metrics ? su.onsets : 0;
  T w0[kMaxWindows], w1[kMaxWindows], ise[kMaxWindows], iae[kMaxWindows], itae[kMaxWindows];
  for (int i = 0; i < nw; ++i) {
    w0[i] = row(su.window[i][0]);
    w1[i] = row(su.window[i][1]);
    ise[i] = iae[i] = itae[i] = T(0.0);
  }
  T onset[kMaxOnsets], peak[kMaxOnsets];
  for (int i = 0; i < no; ++i) {
    onset[i] = row(su.onset[i]);
    peak[i] = T(std::numeric_limits<double>::quiet_NaN());
  }
  T max_abs_u(0.0), control_tv(0.0);
  // The command, settling and steady-state sums per window (the steady-state tail's start per
  // window and lane, NaN for a lane without a tail; the settling threshold² per lane, NaN
  // without one).
  lane::WindowSums<T> sums[kMaxWindows];
  T tail0[kMaxWindows];
  for (int i = 0; i < nw; ++i) tail0[i] = row(su.tail_start[i]);
  std::array<T, M> limit_lo, limit_hi;
  for (int j = 0; j < M; ++j) {
    limit_lo[j] = row(su.limit_lo[j]);
    limit_hi[j] = row(su.limit_hi[j]);
  }
  const T first_fault = row(su.first_onset), threshold_sq = row(su.threshold_sq);
  const Mask settling_lane = threshold_sq == threshold_sq;  // not NaN
  const bool settling = su.kernel_metrics && su.any_settling;
  const bool need_en = no > 0 || (su.kernel_metrics && su.any_tail);
  Mask counting = T(0.0) == T(0.0);
  {
    double c[W];
    for (int l = 0; l < W; ++l) c[l] = live[l] ? 0.0 : 1.0;
    counting = lane::load_lanes<T>(c) == T(0.0);
  }
  const T Tsv(Ts);

  // The actuator model: its output u_a per actuator and lane (0 at t = 0), and its update over a
  // half step, u_a ← u_a + clamp((u_c − u_a)·gain, ±max_step) (ftc/sim/scenario.hpp's
  // ActuatorSteps), towards the command u_c clamped to [limit_lo, limit_hi].
  const bool act = su.actuator;
  const T act_gain = row(su.act_gain), act_step = row(su.act_step), act_neg = -act_step;
  VM ua;
  ua.fill(T(0.0));
  const auto lag = [&](const VM& from, const VM& uc) FTC_HOT_LAMBDA -> VM {
    VM to;
    for (int j = 0; j < M; ++j) {
      T d = (uc[j] - from[j]) * act_gain;
      d = lane::select(d > act_step, act_step, d);
      d = lane::select(d < act_neg, act_neg, d);
      to[j] = from[j] + d;
    }
    return to;
  };

  SampleLanes<N, M> out[32];
  const int block = su.block < 32 ? su.block : 32;
  std::int64_t k = 0;
  while (k < su.samples && live_count > 0) {
    const int n = static_cast<int>(su.samples - k < block ? su.samples - k : block);
    const double* exo = host.inputs(k, n);
    for (int i = 0; i < n; ++i, ++k) {
      const double* e = exo + i * S * 3 * kInstant;
      VN f, f_model;
      plant.drift(x, f, su.mismatch ? &f_model : nullptr);
      // The plant's input now: the actuators' output, or the command held since t_{k-1}.
      const VN a = accel(f, forcing(e, act ? ua : u_prev));
      law::Sample<T, N> m;
      for (int r = 0; r < N; ++r) {
        m.X1[r] = x[r];
        m.X2[r] = x[N + r];
      }
      m.a = a;
      m.f = su.mismatch ? f_model : f;
      VM u;
      if constexpr (kConstantInput) {
        law.step(m, su.G_pinv, u);
      } else {
        T G_pinv[M * N];
        plant.pinv(x, G_pinv);
        law.step(m, static_cast<const T*>(G_pinv), u);
      }
      SampleLanes<N, M>& o = out[i];
      for (int r = 0; r < S2; ++r) lane::store(x[r], o.x[r]);
      for (int r = 0; r < M; ++r) lane::store(u[r], o.u[r]);
      if (su.kernel_metrics) {
        // The accumulators of lanes/metric_lanes.hpp, called as MetricsAccumulator::sample
        // calls them, lanes that have diverged masked out.
        const double td = static_cast<double>(k) * Ts;
        const T t(td);
        const lane::ErrorNorms<T> en2 = lane::error_norms<N, T>(x);
        const lane::ErrorTerms<T> terms = lane::error_terms(Tsv, T(Ts * td), en2);
        const lane::CommandNorms<T> cn = lane::command_norms<M, T>(u);
        const T energy_term = Tsv * cn.sq;
        const Mask saturated = lane::at_limit<M, T>(u, limit_lo, limit_hi);
        const T en = need_en ? lane::sqrt(en2.sq) : T(0.0);
        Mask above = settling_lane, after_fault = settling_lane;
        if (settling) {
          above = en2.sq >= threshold_sq;
          after_fault = settling_lane & (t >= first_fault);
        }
        for (int wi = 0; wi < nw; ++wi) {
          const Mask in = counting & lane::in_window(t, w0[wi], w1[wi]);
          lane::add_error_terms<T>(in, terms, ise[wi], iae[wi], itae[wi]);
          lane::add_command<T>(in, energy_term, cn.max_abs, saturated, sums[wi]);
          if (settling) lane::add_settling<T>(in & after_fault, above, t, sums[wi].settled_from);
          if (su.any_tail) lane::add_tail<T>(in & (t >= tail0[wi]), en, sums[wi]);
        }
        lane::add_max<T>(counting, cn.max_abs, max_abs_u);
        if (k > 0) lane::add_control_tv<M, T>(counting, u, u_prev, control_tv);
        for (int fi = 0; fi < no; ++fi)
          lane::add_peak<T>(counting & (t >= onset[fi]), en, peak[fi]);
      }

      // The substeps, compiled twice: with the actuator model, and without it exactly as before
      // it existed (no test or copy in the loop of a run without one).
      const auto substeps = [&](auto with_actuator) FTC_HOT_LAMBDA {
        constexpr bool A = decltype(with_actuator)::value;
        [[maybe_unused]] VM uc;  // the command within the actuator's range
        if constexpr (A)
          for (int r = 0; r < M; ++r) {
            lane::store(ua[r], o.ua[r]);
            const T c = lane::select(u[r] < limit_lo[r], limit_lo[r], u[r]);
            uc[r] = lane::select(c > limit_hi[r], limit_hi[r], c);
          }
        // Stage 1 of the first substep is at (t, X): f(X) and the inputs are already known.
        const VN a1 = accel(f, forcing(e, A ? ua : u));
        VS k1;
        for (int r = 0; r < N; ++r) {
          k1[r] = x[N + r];
          k1[N + r] = a1[r];
        }
        for (int j = 0; j < S; ++j) {
          const double* ej = e + j * 3 * kInstant;
          if constexpr (A) {
            if (j > 0) k1 = deriv(x, forcing(ej, ua));
            const VM ua_mid = lag(ua, uc);
            const VM ua_end = lag(ua_mid, uc);
            const Forcing mid = forcing(ej + kInstant, ua_mid);
            const Forcing end = forcing(ej + 2 * kInstant, ua_end);
            sim::rk4_advance(
                x, k1, h2, hv, h6, [&](const VS& s) FTC_HOT_LAMBDA { return deriv(s, mid); },
                [&](const VS& s) FTC_HOT_LAMBDA { return deriv(s, end); });
            ua = ua_end;
          } else {
            if (j > 0) k1 = deriv(x, forcing(ej, u));
            const Forcing mid = forcing(ej + kInstant, u);
            const Forcing end = forcing(ej + 2 * kInstant, u);
            sim::rk4_advance(
                x, k1, h2, hv, h6, [&](const VS& s) FTC_HOT_LAMBDA { return deriv(s, mid); },
                [&](const VS& s) FTC_HOT_LAMBDA { return deriv(s, end); });
          }
        }
      };
      if (act)
        substeps(std::true_type{});
      else
        substeps(std::false_type{});
      u_prev = u;

      Mask inside = lane::abs(x[0]) <= T(1e6);  // false for NaN
      for (int r = 1; r < S2; ++r) inside = inside & (lane::abs(x[r]) <= T(1e6));
      if (lane::all(inside)) [[likely]] {
        for (int l = 0; l < W; ++l) o.diverged[l] = false;
        continue;
      }
      // Lanes that left the bounds: those still counting end here (their final state is this
      // one), and every such lane restarts from X(0) with a reset controller.
      lane::store_mask(lane::mask_not(inside), o.diverged);
      for (int l = 0; l < W; ++l) {
        if (!o.diverged[l] || !live[l]) continue;
        live[l] = false;
        --live_count;
        fin.samples[l] = k + 1;
        fin.diverged[l] = true;
        fin.diverged_at[l] = static_cast<double>(k) * Ts + Ts;
        for (int r = 0; r < S2; ++r) fin.x[r][l] = lane::lane_of(x[r], l);
      }
      counting = counting & inside;
      for (int r = 0; r < S2; ++r) x[r] = lane::select(inside, x[r], x0[r]);
      for (int r = 0; r < M; ++r) u_prev[r] = lane::select(inside, u_prev[r], T(0.0));
      if (act)
        for (int r = 0; r < M; ++r) ua[r] = lane::select(inside, ua[r], T(0.0));
      law.reset_lanes(inside);
    }
    if (su.want_samples) host.samples(k - n, n, out);
  }
  // Each sum to its field's slot of the metrics record (ftc/sim/metrics_record.hpp).
  constexpr std::size_t kIse = metric_slot("ise"), kIae = metric_slot("iae"),
                        kItae = metric_slot("itae"), kMaxAbsU = metric_slot("max_abs_u"),
                        kControlTv = metric_slot("control_tv"),
                        kPeak = metric_slot("peak_error_after_fault"),
                        kEnergy = metric_slot("control_energy"),
                        kPeakCommand = metric_slot("peak_command"),
                        kSaturation = metric_slot("saturation_fraction"),
                        kSettling = metric_slot("settling_time"),
                        kSteady = metric_slot("steady_state_error");
  for (int l = 0; l < W; ++l) {
    for (int wi = 0; wi < nw; ++wi) {
      fin.window_field[kIse][wi][l] = lane::lane_of(ise[wi], l);
      fin.window_field[kIae][wi][l] = lane::lane_of(iae[wi], l);
      fin.window_field[kItae][wi][l] = lane::lane_of(itae[wi], l);
      const lane::WindowSums<T>& s = sums[wi];
      lane::WindowSums<double> one;
      one.energy = lane::lane_of(s.energy, l);
      one.peak = lane::lane_of(s.peak, l);
      one.saturated = lane::lane_of(s.saturated, l);
      one.samples = lane::lane_of(s.samples, l);
      one.settled_from = lane::lane_of(s.settled_from, l);
      one.tail_sum = lane::lane_of(s.tail_sum, l);
      one.tail_samples = lane::lane_of(s.tail_samples, l);
      const lane::WindowMetrics w = lane::finish_window(one, su.first_onset[l]);
      fin.window_field[kEnergy][wi][l] = w.control_energy;
      fin.window_field[kPeakCommand][wi][l] = w.peak_command;
      fin.window_field[kSaturation][wi][l] = w.saturation_fraction;
      fin.window_field[kSettling][wi][l] = w.settling_time;
      fin.window_field[kSteady][wi][l] = w.steady_state_error;
    }
    for (int fi = 0; fi < no; ++fi) fin.fault_field[kPeak][fi][l] = lane::lane_of(peak[fi], l);
    fin.run_field[kMaxAbsU][l] = lane::lane_of(max_abs_u, l);
    fin.run_field[kControlTv][l] = lane::lane_of(control_tv, l);
  }
  for (int l = 0; l < W; ++l)
    if (live[l] || l >= su.lanes)
      for (int r = 0; r < S2; ++r) fin.x[r][l] = lane::lane_of(x[r], l);
}

// The kernel of one instruction set: the law and the kind of inputs chosen once per pack.
template <class T, class P, template <class, int, int> class Law, int N, int M>
void run_law(const PackSetup<N, M>& su, PackHost<N, M>& host, PackFinal<N, M>& fin) {
  if (su.shared_inputs)
    run_closed_loop<T, P, Law, true>(su, host, fin);
  else
    run_closed_loop<T, P, Law, false>(su, host, fin);
}

template <class T, class P, int N, int M>
void run_pack(const PackSetup<N, M>& su, PackHost<N, M>& host, PackFinal<N, M>& fin) {
  visit_controller_type(su.configs[0]->type, [&](auto t) {
    run_law<T, P, law::LawOf<decltype(t)::value>::template type>(su, host, fin);
  });
}

// The lane type of the instruction set this file is compiled for (FTC_LANE_ARCH, set by
// ftc_plant_kernels() in sim_core/CMakeLists.txt): one double without it.
#if defined(FTC_LANE_ARCH)
using NativeLane = xsimd::batch<double, xsimd::FTC_LANE_ARCH>;
#else
using NativeLane = double;
#endif

template <class P, int N, int M>
void pack_kernel(const PackSetup<N, M>& su, PackHost<N, M>& host, PackFinal<N, M>& fin) {
  run_pack<NativeLane, P>(su, host, fin);
}

}  // namespace FTC_ISA_NS
}  // namespace ftc::sim::detail

// In a plant's lanes file, after its PlantLanes<P>: the kernel of P for the instruction set the
// file is compiled for (lanes/pack.hpp declares one per instruction set).
#define FTC_PLANT_KERNEL(P)                                                                     \
  template void ftc::sim::detail::FTC_ISA_NS::pack_kernel<P, ftc::sim::detail::PlantLanes<P>::N, \
                                                          ftc::sim::detail::PlantLanes<P>::M>(  \
      const ftc::sim::detail::PackSetup<ftc::sim::detail::PlantLanes<P>::N,                    \
                                        ftc::sim::detail::PlantLanes<P>::M>&,                  \
      ftc::sim::detail::PackHost<ftc::sim::detail::PlantLanes<P>::N,                           \
                                 ftc::sim::detail::PlantLanes<P>::M>&,                         \
      ftc::sim::detail::PackFinal<ftc::sim::detail::PlantLanes<P>::N,                          \
                                  ftc::sim::detail::PlantLanes<P>::M>&);
