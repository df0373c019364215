#pragma once
// The spacecraft's closed loop (SPEC §4) for W simulations in lockstep, one per lane of T, with
// the control law Law (controllers/laws.hpp). Included by the kernel files only, each compiled
// for one instruction set (lanes/pack.hpp says what crosses the boundary). With T = double it
// is the scalar simulator of the spacecraft: simulate() and the SIMD lanes run this same code,
// which is why a lane reproduces the scalar run to the last bit.
//
//   per sample k, t = k Ts, for every lane:
//     a_k = f(X) + G·applied(t, u_{k-1}) + Δ(t)     acceleration sensor, before the new command
//     u_k = law(X1, X2, a_k, f_model(X))
//     substeps × RK4 with u_k held; faults and Δ at each stage time
//     a lane with |X_i| > 1e6, inf or NaN has diverged: it stops counting, restarts from X(0)
//     with a reset controller (so that it takes no slow paths), and the host ignores it
//   the pack ends when every lane has diverged or all samples are done
#include <array>
#include <cstdint>
#include <limits>

#include "controllers/laws.hpp"
#include "lanes/elementary.hpp"
#include "lanes/pack.hpp"
#include "plants/spacecraft_dynamics.hpp"

namespace ftc::sim::detail {
inline namespace FTC_ISA_NS {

// sin and cos of the attitude angles, which move in small steps, as in SinCosTracker
// (sincos.hpp): from an anchor by the Taylor series of sin δ and cos δ for |δ| ≤ 0.02, the
// anchor renewed (in the lanes that need it) otherwise.
template <class T>
[[gnu::noinline]] void anchor_sincos(const T& x, T& s, T& c) {
  lane::sincos(x, s, c);
}

template <class T>
struct AngleTracker {
  T anchor = T(std::numeric_limits<double>::quiet_NaN());
  T s = T(0.0), c = T(1.0);

  FTC_HOT_INLINE void eval(const T& x, T& so, T& co) {
    const lane::Mask<T> near = lane::abs(x - anchor) <= T(0.02);  // false for NaN
    if (!lane::all(near)) [[unlikely]] {
      T sn, cn;
      anchor_sincos(x, sn, cn);
      anchor = lane::select(near, anchor, x);
      s = lane::select(near, s, sn);
      c = lane::select(near, c, cn);
    }
    const T d = x - anchor;
    const T d2 = d * d;
    const T sd = d * (T(1.0) + d2 * (T(-1.0 / 6) + d2 * (T(1.0 / 120) + d2 * T(-1.0 / 5040))));
    const T cd =
        T(1.0) + d2 * (T(-0.5) + d2 * (T(1.0 / 24) + d2 * (T(-1.0 / 720) + d2 * T(1.0 / 40320))));
    so = s * cd + c * sd;
    co = c * cd - s * sd;
  }
};

template <class T, template <class, int, int> class Law, bool SharedInputs>
void run_spacecraft_pack(const PackSetup& su, PackHost& host, PackFinal& fin) {
  constexpr int W = lane::kWidth<T>;
  using Mask = lane::Mask<T>;
  using V3 = std::array<T, 3>;
  using V4 = std::array<T, 4>;
  using V6 = std::array<T, 6>;
  static_assert(W <= kMaxLanes);

  const ControllerConfig* configs[W];
  for (int l = 0; l < W; ++l) configs[l] = su.configs[l < su.lanes ? l : 0];
  Law<T, 3, 4> law(configs, su.Ts);

  const auto row = [](const double* r) { return lane::load_lanes<T>(r); };
  // Row r of an instant's exogenous inputs (ExoRows): one value for every lane, or each lane's own.
  constexpr int kStride = ExoRows::stride(SharedInputs, W);
  constexpr int kInstant = ExoRows::kCount * kStride;
  const auto input = [](const double* e, int r) FTC_HOT_LAMBDA {
    if constexpr (SharedInputs)
      return T(e[r]);
    else
      return lane::load_lanes<T>(e + r * kStride);
  };
  const T kx = row(su.truth[0]), ky = row(su.truth[1]), kz = row(su.truth[2]), w = row(su.truth[3]);
  const T mkx = row(su.model[0]), mky = row(su.model[1]), mkz = row(su.model[2]),
          mw = row(su.model[3]);
  const T sat = row(su.saturation);
  V6 x0;
  for (int i = 0; i < 6; ++i) x0[i] = row(su.x0[i]);
  T G[12];
  for (int i = 0; i < 12; ++i) G[i] = T(su.G[i]);

  const double Ts = su.Ts;
  const double h = Ts / su.substeps;
  const T hv(h), h2(0.5 * h), h6(h / 6.0);
  const int S = su.substeps;

  std::array<AngleTracker<T>, 3> trig;
  // f(X) of the simulated plant, and of the model when they differ, from one set of sines.
  const auto drift = [&](const V6& x, V3& f, V3* f_model) FTC_HOT_LAMBDA {
    T s[3], c[3];
    for (int i = 0; i < 3; ++i) trig[i].eval(x[i], s[i], c[i]);
    T out[3];
    spacecraft_f<T>(kx, ky, kz, w, x[3], x[4], x[5], s, c, out);
    f = {out[0], out[1], out[2]};
    if (f_model) {
      spacecraft_f<T>(mkx, mky, mkz, mw, x[3], x[4], x[5], s, c, out);
      *f_model = {out[0], out[1], out[2]};
    }
  };
  // dX2/dt = f(X) + G u + Δ(t), u the command u_d after the faults and saturation at one
  // instant. The forcing G u and Δ depend on the instant and the held command only, so the two
  // midpoint stages share it.
  struct Forcing {
    V3 Gu, dist;
  };
  const auto forcing = [&](const double* e, const V4& u_d) FTC_HOT_LAMBDA -> Forcing {
    V4 u;
    for (int j = 0; j < 4; ++j) {
      const T v = input(e, ExoRows::kGain + j) * u_d[j] + input(e, ExoRows::kOffset + j);
      const T lo = lane::select(v < -sat, -sat, v);
      u[j] = lane::select(lo > sat, sat, lo);
    }
    Forcing F;
    for (int i = 0; i < 3; ++i) {
      T g = G[i * 4] * u[0];
      for (int j = 1; j < 4; ++j) g = g + G[i * 4 + j] * u[j];
      F.Gu[i] = g;
      F.dist[i] = input(e, ExoRows::kDist + i);
    }
    return F;
  };
  const auto accel = [&](const V3& f, const Forcing& F) FTC_HOT_LAMBDA -> V3 {
    return {(f[0] + F.Gu[0]) + F.dist[0], (f[1] + F.Gu[1]) + F.dist[1],
            (f[2] + F.Gu[2]) + F.dist[2]};
  };
  const auto deriv = [&](const V6& x, const Forcing& F) FTC_HOT_LAMBDA -> V6 {
    V3 f;
    drift(x, f, nullptr);
    const V3 a = accel(f, F);
    return {x[3], x[4], x[5], a[0], a[1], a[2]};
  };

  V6 x = x0;
  V4 u_prev{T(0.0), T(0.0), T(0.0), T(0.0)};
  bool live[W];  // lanes still counting
  for (int l = 0; l < W; ++l) live[l] = l < su.lanes;
  int live_count = su.lanes;
  for (int l = 0; l < W; ++l) {
    fin.samples[l] = su.samples;
    fin.diverged[l] = false;
  }

  // The metrics, in the operations and order of MetricsAccumulator::sample (ftc/sim/metrics.hpp),
  // lanes that have diverged masked out.
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
  Mask counting = T(0.0) == T(0.0);
  {
    double c[W];
    for (int l = 0; l < W; ++l) c[l] = live[l] ? 0.0 : 1.0;
    counting = lane::load_lanes<T>(c) == T(0.0);
  }
  const T Tsv(Ts);

  SampleLanes out[32];
  const int block = su.block < 32 ? su.block : 32;
  std::int64_t k = 0;
  while (k < su.samples && live_count > 0) {
    const int n = static_cast<int>(su.samples - k < block ? su.samples - k : block);
    const double* exo = host.inputs(k, n);
    for (int i = 0; i < n; ++i, ++k) {
      const double* e = exo + i * S * 3 * kInstant;
      V3 f, f_model;
      drift(x, f, su.mismatch ? &f_model : nullptr);
      const V3 a = accel(f, forcing(e, u_prev));
      law::Sample<T, 3> m;
      m.X1 = {x[0], x[1], x[2]};
      m.X2 = {x[3], x[4], x[5]};
      m.a = a;
      m.f = su.mismatch ? f_model : f;
      V4 u;
      law.step(m, su.G_pinv, u);
      SampleLanes& o = out[i];
      for (int r = 0; r < 6; ++r) lane::store(x[r], o.x[r]);
      for (int r = 0; r < 4; ++r) lane::store(u[r], o.u[r]);
      if (su.kernel_metrics) {
        const double td = static_cast<double>(k) * Ts;
        const T t(td);
        const T e2 = (x[0] * x[0] + x[1] * x[1]) + x[2] * x[2];
        const T e1 = (lane::abs(x[0]) + lane::abs(x[1])) + lane::abs(x[2]);
        const T ise_k = Tsv * e2, iae_k = Tsv * e1, itae_k = T(Ts * td) * e1;
        for (int wi = 0; wi < nw; ++wi) {
          const Mask in = counting & (t >= w0[wi]) & (t < w1[wi]);
          ise[wi] = lane::select(in, ise[wi] + ise_k, ise[wi]);
          iae[wi] = lane::select(in, iae[wi] + iae_k, iae[wi]);
          itae[wi] = lane::select(in, itae[wi] + itae_k, itae[wi]);
        }
        T u_max = lane::abs(u[0]);
        for (int j = 1; j < 4; ++j) {
          const T a_j = lane::abs(u[j]);
          u_max = lane::select(u_max < a_j, a_j, u_max);
        }
        max_abs_u = lane::select(counting & (max_abs_u < u_max), u_max, max_abs_u);
        if (k > 0) {
          T d2 = (u[0] - u_prev[0]) * (u[0] - u_prev[0]);
          for (int j = 1; j < 4; ++j) d2 = d2 + (u[j] - u_prev[j]) * (u[j] - u_prev[j]);
          control_tv = lane::select(counting, control_tv + lane::sqrt(d2), control_tv);
        }
        if (no > 0) {
          const T en = lane::sqrt(e2);
          for (int fi = 0; fi < no; ++fi) {
            const Mask rising = counting & (t >= onset[fi]) & lane::mask_not(peak[fi] >= en);
            peak[fi] = lane::select(rising, en, peak[fi]);
          }
        }
      }

      // Stage 1 of the first substep is at (t, X): f(X) and the inputs are already known.
      const V3 a1 = accel(f, forcing(e, u));
      V6 k1{x[3], x[4], x[5], a1[0], a1[1], a1[2]};
      for (int j = 0; j < S; ++j) {
        const double* ej = e + j * 3 * kInstant;
        if (j > 0) k1 = deriv(x, forcing(ej, u));
        V6 xs;
        for (int r = 0; r < 6; ++r) xs[r] = x[r] + h2 * k1[r];
        const Forcing mid = forcing(ej + kInstant, u);
        const V6 k2 = deriv(xs, mid);
        for (int r = 0; r < 6; ++r) xs[r] = x[r] + h2 * k2[r];
        const V6 k3 = deriv(xs, mid);
        for (int r = 0; r < 6; ++r) xs[r] = x[r] + hv * k3[r];
        const V6 k4 = deriv(xs, forcing(ej + 2 * kInstant, u));
        for (int r = 0; r < 6; ++r) {
          T sum = k1[r] + T(2.0) * k2[r];
          sum = sum + T(2.0) * k3[r];
          sum = sum + k4[r];
          x[r] = x[r] + h6 * sum;
        }
      }
      u_prev = u;

      Mask inside = lane::abs(x[0]) <= T(1e6);  // false for NaN
      for (int r = 1; r < 6; ++r) inside = inside & (lane::abs(x[r]) <= T(1e6));
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
        for (int r = 0; r < 6; ++r) fin.x[r][l] = lane::lane_of(x[r], l);
      }
      counting = counting & inside;
      for (int r = 0; r < 6; ++r) x[r] = lane::select(inside, x[r], x0[r]);
      for (int r = 0; r < 4; ++r) u_prev[r] = lane::select(inside, u_prev[r], T(0.0));
      law.reset_lanes(inside);
    }
    if (su.want_samples) host.samples(k - n, n, out);
  }
  for (int l = 0; l < W; ++l) {
    for (int wi = 0; wi < nw; ++wi) {
      fin.ise[wi][l] = lane::lane_of(ise[wi], l);
      fin.iae[wi][l] = lane::lane_of(iae[wi], l);
      fin.itae[wi][l] = lane::lane_of(itae[wi], l);
    }
    for (int fi = 0; fi < no; ++fi) fin.peak[fi][l] = lane::lane_of(peak[fi], l);
    fin.max_abs_u[l] = lane::lane_of(max_abs_u, l);
    fin.control_tv[l] = lane::lane_of(control_tv, l);
  }
  for (int l = 0; l < W; ++l)
    if (live[l] || l >= su.lanes)
      for (int r = 0; r < 6; ++r) fin.x[r][l] = lane::lane_of(x[r], l);
}

// The kernel of one instruction set: the law and the kind of inputs chosen once per pack.
template <class T, template <class, int, int> class Law>
void run_law(const PackSetup& su, PackHost& host, PackFinal& fin) {
  if (su.shared_inputs)
    run_spacecraft_pack<T, Law, true>(su, host, fin);
  else
    run_spacecraft_pack<T, Law, false>(su, host, fin);
}

template <class T>
void run_pack(const PackSetup& su, PackHost& host, PackFinal& fin) {
  switch (su.configs[0]->type) {
    case ControllerType::nftsmc:
      return run_law<T, law::Nftsmc>(su, host, fin);
    case ControllerType::fosmc:
      return run_law<T, law::Fosmc>(su, host, fin);
    case ControllerType::pi_fosmc:
      return run_law<T, law::PiFosmc>(su, host, fin);
    case ControllerType::adaptive_neural_pi_fosmc:
      return run_law<T, law::AdaptiveNeuralPiFosmc>(su, host, fin);
  }
}

}  // namespace FTC_ISA_NS
}  // namespace ftc::sim::detail
