#pragma once
// The closed loop of SPEC §4, written once: for W simulations of one plant in lockstep, one per
// lane of T, with a control law (controllers/laws.hpp) and the plant's lane code. Everything
// that simulates runs it: the batch kernels (T a SIMD batch, every plant, every instruction
// set), AnyPlant::simulate (T = double, one lane of the scalar kernel) and the runtime's
// sim::simulate with a Controller object (one lane, the controller as the law: ObjectLaw). So a
// lane reproduces the scalar run, and a runtime controller a tuning run's lane, to the last bit.
// ClosedLoop::step() advances one sample (the acceleration sensor, the law, the metrics, the
// faults and limits, RK4); run_closed_loop() calls it for every sample of a pack.
//
// A plant gives its dynamics as lane code, PlantLanes<P> (plants/<plant>_lanes.cpp), the way
// controllers/laws.hpp gives the laws: the constants per lane (the PackSetup's truth and model
// rows, read once) apart from what changes (the state X, which the loop owns, and the plant's
// scratch space, such as angle trackers). PlantLanes<P> gives the plant's shape, static
// constexpr int N, M, and for the lane type T a class Lanes<T> with
//   static constexpr bool kConstantInput;
//   static constexpr bool kTrimmed;   actuators about an operating point (PackSetup::u0, lo, hi)
//   Lanes(const PackSetup<N, M>&)                       the constants of every lane
//   void drift(const V<2N>& x, V<N>& f, V<N>* f_model)  f(X) of the truth (and of the model)
// and, when G depends on X (kConstantInput false; else the loop uses PackSetup::G and G_pinv),
//   void input(const V<M>& u, V<N>& Gu)  G(X) u at the X of the last drift() call, summed
//                                        G(i,0) u0 + G(i,1) u1 + ... in that order
//   void pinv(const V<2N>& x, T* out)    the model's G⁺(X), row-major m×n, as Plant::G_pinv
// and optionally, for a model valid only in part of the state space (the rigid body's Euler
// angles),
//   void observe(const V<2N>& x, Mask counting)   X at each sample, in the lanes still counting
//   bool model_invalid(int lane)                  whether X left the model's validity
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

// The closed loop of a pack: the constants of its lanes (from the PackSetup) and the loop's state
// (X, the held command, the actuators' output, which lanes still count), over the plant's lane
// code, the control law and the metrics' sums it is given. step() advances every lane by one
// sample, as MuJoCo's mj_step advances its data by one step; run_closed_loop() calls it for
// every sample. Plant is a PlantLanes<P>::Lanes<T> (or ObjectPlantLanes); Law has
// step(law::Sample, G⁺, u) and reset_lanes(keep) (controllers/laws.hpp, or ObjectLaw).
// Every member function is inlined and the loop's address is never taken, so that the compiler
// keeps its state and constants in registers, as it would local variables (a loop object that
// escaped cost the scalar kernels 3 to 6 % in reloads).
template <class T, class Plant, class Law, bool SharedInputs, int N, int M>
class ClosedLoop {
  static constexpr int S2 = 2 * N;
  static constexpr bool kConstantInput = Plant::kConstantInput;
  static constexpr bool kTrimmed = Plant::kTrimmed;
  static constexpr int W = lane::kWidth<T>;
  static_assert(W <= kMaxLanes);
  using Mask = lane::Mask<T>;
  using VN = std::array<T, N>;
  using VM = std::array<T, M>;
  using VS = std::array<T, S2>;
  using Exo = ExoRows<N, M>;
  // Row r of an instant's exogenous inputs (ExoRows): one value for every lane, or each lane's.
  static constexpr int kStride = Exo::stride(SharedInputs, W);

 public:
  // The values of an instant's inputs, then the three instants (start, midpoint, end) of a
  // substep and the substeps of a sample: sample i of a block of inputs is at
  // exo + i · kSample(substeps).
  static constexpr int kInstant = Exo::kCount * kStride;
  static constexpr int sample_stride(int substeps) { return substeps * 3 * kInstant; }

  FTC_HOT_INLINE ClosedLoop(const PackSetup<N, M>& su, Plant& plant, Law& law,
                            MetricLanes<T, N, M>& metrics)
      : su_(su),
        plant_(plant),
        sensed_(plant),
        law_(law),
        metrics_(metrics),
        Ts_(su.Ts),
        hv_(su.Ts / su.substeps),
        h2_(0.5 * (su.Ts / su.substeps)),
        h6_((su.Ts / su.substeps) / 6.0),
        S_(su.substeps),
        act_(su.actuator),
        act_gain_(row(su.act_gain)),
        act_step_(row(su.act_step)),
        act_neg_(-act_step_),
        sensors_(su.sensors),
        delay_(su.delay),
        differentiated_(su.differentiated),
        angle_step_(row(su.angle_step)),
        rate_step_(row(su.rate_step)),
        lowpass_gain_(row(su.lowpass_gain)) {
    if constexpr (kTrimmed)
      for (int j = 0; j < M; ++j) u0_[j] = row(su.u0[j]);
    for (int i = 0; i < S2; ++i) x0_[i] = row(su.x0[i]);
    if constexpr (kConstantInput)
      for (int i = 0; i < N * M; ++i) G_[i] = T(su.G[i]);
    for (int j = 0; j < M; ++j) {
      limit_lo_[j] = row(su.metrics.limit_lo[j]);
      limit_hi_[j] = row(su.metrics.limit_hi[j]);
    }
    x_ = x0_;
    rate_prev_.fill(T(0.0));
    lowpass_.fill(T(0.0));
    u_prev_.fill(T(0.0));
    ua_.fill(T(0.0));
    live_count_ = su.lanes;
    double c[W];
    for (int l = 0; l < W; ++l) {
      live_[l] = l < su.lanes;
      c[l] = live_[l] ? 0.0 : 1.0;
      samples_[l] = su.samples;
      diverged_[l] = false;
      diverged_at_[l] = 0.0;
    }
    counting_ = lane::load_lanes<T>(c) == T(0.0);
  }

  // Whether some lane still counts (the others have diverged).
  FTC_HOT_INLINE bool running() const { return live_count_ > 0; }

  // Sample k of every lane, t = k·Ts, `e` its exogenous inputs (sample_stride values), `nz` its
  // measurement noise (with sensors: 3N rows of kStride values, PackHost::noise):
  //   a_k = f(X) + G(X)·applied(t, u_{k-1}) + Δ(t)   the acceleration sensor, before the command
  //   u_k = law(X1, X2, a_k, f_model(X), G⁺_model(X))
  //   the metrics of (t, X, u_k)
  //   substeps × RK4 with u_k held; faults and Δ at each stage time
  // With sensors (ftc/sim/sensors.hpp) u_k = law(X1m, X2m, a_k or am, f_model(Xm), G⁺_model(Xm)),
  // Xm = (X1m, X2m) the measurement the controller reads at sample k; the metrics keep X.
  // With an actuator model (PackSetup::actuator, docs/model.md) the plant is driven by the
  // actuators' output u_a instead of the held command: u_a(t_k) in a_k and at each stage, u_a
  // stepped on the half-step grid towards the command clamped to the actuator's range. A lane
  // with |X_i| > 1e6, inf or NaN has diverged: it stops counting, restarts from X(0) with a reset
  // controller (so that it takes no slow paths), and its results are those at that step. `o`
  // receives X(t_k), u_k, u_a(t_k) and the lanes that diverged in this step.
  FTC_HOT_INLINE void step(std::int64_t k, const double* e, const double* nz,
                           SampleLanes<N, M>& o) {
    VN f, f_model{};
    plant_.drift(x_, f, su_.mismatch && !sensors_ ? &f_model : nullptr);
    if constexpr (requires { plant_.observe(x_, counting_); }) plant_.observe(x_, counting_);
    // The plant's input now: the actuators' output, or the command held since t_{k-1}.
    const VN a = accel(f, forcing(e, act_ ? ua_ : u_prev_));
    law::Sample<T, N> m;
    m.t = static_cast<double>(k) * Ts_;
    [[maybe_unused]] T G_pinv[M * N];
    if (sensors_) [[unlikely]] {
      // What the controller reads, and its model terms at that state, from a copy of the
      // plant's lane code (sensed_): a plant's scratch (angle trackers, the state input() and
      // pinv() read) follows the true state alone, so the truth's bits do not depend on the
      // measurement. A branch per sample rather than a second compiled copy of the loop: the
      // copy took a kernel's compile from 24.5 to 54 s (28 s with the branch).
      measure(k, nz, m);
      if (!differentiated_) m.a = a;
      VS xm;
      for (int r = 0; r < N; ++r) {
        xm[r] = m.X1[r];
        xm[N + r] = m.X2[r];
      }
      VN fm, fm_model{};
      sensed_.drift(xm, fm, su_.mismatch ? &fm_model : nullptr);
      m.f = su_.mismatch ? fm_model : fm;
      if constexpr (!kConstantInput) sensed_.pinv(xm, G_pinv);
    } else {
      for (int r = 0; r < N; ++r) {
        m.X1[r] = x_[r];
        m.X2[r] = x_[N + r];
      }
      m.a = a;
      m.f = su_.mismatch ? f_model : f;
      if constexpr (!kConstantInput) plant_.pinv(x_, G_pinv);
    }
    VM u;
    if constexpr (kConstantInput)
      law_.step(m, su_.G_pinv, u);
    else
      law_.step(m, static_cast<const T*>(G_pinv), u);
    for (int r = 0; r < S2; ++r) lane::store(x_[r], o.x[r]);
    for (int r = 0; r < M; ++r) lane::store(u[r], o.u[r]);
    metrics_.sample(counting_, k, Ts_, x_, u, u_prev_);
    if (act_)
      substeps<true>(e, f, u, o);
    else
      substeps<false>(e, f, u, o);
    u_prev_ = u;

    Mask inside = lane::abs(x_[0]) <= T(1e6);  // false for NaN
    for (int r = 1; r < S2; ++r) inside = inside & (lane::abs(x_[r]) <= T(1e6));
    if (lane::all(inside)) [[likely]] {
      for (int l = 0; l < W; ++l) o.diverged[l] = false;
      return;
    }
    // Lanes that left the bounds: those still counting end here (their final state is this
    // one), and every such lane restarts from X(0) with a reset controller.
    lane::store_mask(lane::mask_not(inside), o.diverged);
    for (int l = 0; l < W; ++l) {
      if (!o.diverged[l] || !live_[l]) continue;
      live_[l] = false;
      --live_count_;
      samples_[l] = k + 1;
      diverged_[l] = true;
      diverged_at_[l] = static_cast<double>(k) * Ts_ + Ts_;
      for (int r = 0; r < S2; ++r) x_end_[r][l] = lane::lane_of(x_[r], l);
    }
    counting_ = counting_ & inside;
    for (int r = 0; r < S2; ++r) x_[r] = lane::select(inside, x_[r], x0_[r]);
    for (int r = 0; r < M; ++r) u_prev_[r] = lane::select(inside, u_prev_[r], T(0.0));
    if (act_)
      for (int r = 0; r < M; ++r) ua_[r] = lane::select(inside, ua_[r], T(0.0));
    if (sensors_) reset_sensors(inside);
    law_.reset_lanes(inside);
  }

  // Each lane's end: its samples, final state, divergence and metrics.
  FTC_HOT_INLINE void finish(PackFinal<N, M>& fin) const {
    for (int l = 0; l < W; ++l) {
      fin.samples[l] = samples_[l];
      fin.diverged[l] = diverged_[l];
      fin.diverged_at[l] = diverged_at_[l];
      if constexpr (requires { plant_.model_invalid(l); })
        fin.model_invalid[l] = plant_.model_invalid(l);
      for (int r = 0; r < S2; ++r)
        fin.x[r][l] = live_[l] || l >= su_.lanes ? lane::lane_of(x_[r], l) : x_end_[r][l];
      if (l < su_.lanes) metrics_.write(l, su_.metrics.first_onset[l], fin.metrics);
    }
  }

 private:
  FTC_HOT_INLINE static T row(const double* r) { return lane::load_lanes<T>(r); }
  FTC_HOT_INLINE static T input(const double* e, int r) {
    if constexpr (SharedInputs)
      return T(e[r]);
    else
      return lane::load_lanes<T>(e + r * kStride);
  }

  // dX2/dt = f(X) + G u + Δ(t), u the command u_d within its limits, then the faults, then the
  // limits again (ftc/sim/faults.hpp, SPEC §17.1), at one instant: a weakened actuator delivers at
  // most (1 − ρ) of its limit. The applied u (and with a constant G the forcing G u) and Δ depend
  // on the instant and the held command only, so the two midpoint stages share them.
  struct NoGu {};
  struct Forcing {
    [[no_unique_address]] std::conditional_t<kConstantInput, VN, NoGu> Gu;
    VN dist;
    VM u;
  };
  FTC_HOT_INLINE Forcing forcing(const double* e, const VM& u_d) const {
    Forcing F;
    for (int j = 0; j < M; ++j) {
      const T lo = limit_lo_[j], hi = limit_hi_[j];
      const T c0 = lane::select(u_d[j] < lo, lo, u_d[j]);
      const T c = lane::select(c0 > hi, hi, c0);
      T v;
      if constexpr (kTrimmed)  // the faults act on the physical output u0 + u
        v = (input(e, Exo::kGain + j) * (u0_[j] + c) + input(e, Exo::kOffset + j)) - u0_[j];
      else
        v = input(e, Exo::kGain + j) * c + input(e, Exo::kOffset + j);
      const T w = lane::select(v < lo, lo, v);
      F.u[j] = lane::select(w > hi, hi, w);
    }
    for (int i = 0; i < N; ++i) {
      if constexpr (kConstantInput) {
        T g = G_[i * M] * F.u[0];
        for (int j = 1; j < M; ++j) g = g + G_[i * M + j] * F.u[j];
        F.Gu[i] = g;
      }
      F.dist[i] = input(e, Exo::kDist + i);
    }
    return F;
  }
  // The acceleration at the state of the plant's last drift() call.
  FTC_HOT_INLINE VN accel(const VN& f, const Forcing& F) {
    VN a;
    if constexpr (kConstantInput) {
      for (int i = 0; i < N; ++i) a[i] = (f[i] + F.Gu[i]) + F.dist[i];
    } else {
      VN Gu;
      plant_.input(F.u, Gu);
      for (int i = 0; i < N; ++i) a[i] = (f[i] + Gu[i]) + F.dist[i];
    }
    return a;
  }
  FTC_HOT_INLINE VS deriv(const VS& x, const Forcing& F) {
    VN f;
    plant_.drift(x, f, nullptr);
    const VN a = accel(f, F);
    VS d;
    for (int i = 0; i < N; ++i) {
      d[i] = x[N + i];
      d[N + i] = a[i];
    }
    return d;
  }
  // The sensors (ftc/sim/sensors.hpp): the measurement of sample k, X1m = q_a(X1 + noise), X2m =
  // q_r(X2 + noise) and, differentiated, am the low-passed difference of X2m; with a delay d,
  // kept in the ring and read back from sample max(0, k − d). Into m's X1, X2 (and a).
  FTC_HOT_INLINE static T quantize(const T& x, const T& q) {
    // q · round(x / q), ties away from zero; x where q = 0. For 0 ≤ a < 2^52, (a + 2^52) − 2^52
    // is a rounded to a whole number, ties to even (the ulp of the sum is 1): a tie it took down
    // is taken up. a ≥ 2^52 is whole already.
    const T t = x / q;
    const T a = lane::abs(t);
    T r = (a + T(0x1p52)) - T(0x1p52);
    r = lane::select(r - a == T(-0.5), r + T(1.0), r);
    r = lane::select(a >= T(0x1p52), a, r);
    r = lane::select(t < T(0.0), -r, r);
    return lane::select(q > T(0.0), q * r, x);
  }
  FTC_HOT_INLINE T noise_row(const double* nz, int r) const {
    if constexpr (SharedInputs)
      return T(nz[r]);
    else
      return lane::load_lanes<T>(nz + r * kStride);
  }
  FTC_HOT_INLINE void measure(std::int64_t k, const double* nz, law::Sample<T, N>& m) {
    std::array<T, 3 * N> now;
    for (int i = 0; i < N; ++i) {
      now[i] = quantize(x_[i] + noise_row(nz, i), angle_step_);
      // §18's order: (X2 + b_k) + σ_r z.
      now[N + i] = quantize((x_[N + i] + noise_row(nz, N + i)) + noise_row(nz, 2 * N + i),
                            rate_step_);
    }
    if (differentiated_)
      for (int i = 0; i < N; ++i) {
        const T d = k == 0 ? T(0.0) : (now[N + i] - rate_prev_[i]) / T(Ts_);
        lowpass_[i] = lowpass_[i] + lowpass_gain_ * (d - lowpass_[i]);
        rate_prev_[i] = now[N + i];
      }
    for (int i = 0; i < N; ++i) now[2 * N + i] = lowpass_[i];  // 0 unless differentiated
    if (delay_ > 0) {
      const int slots = delay_ + 1;
      double* ring = su_.ring;
      for (int r = 0; r < 3 * N; ++r)
        lane::store(now[r], ring + (static_cast<std::size_t>(k % slots) * 3 * N + r) * kMaxLanes);
      const std::int64_t from = k < delay_ ? 0 : (k - delay_) % slots;
      for (int r = 0; r < 3 * N; ++r)
        now[r] = lane::load_lanes<T>(ring + (static_cast<std::size_t>(from) * 3 * N + r) *
                                                kMaxLanes);
    }
    for (int i = 0; i < N; ++i) {
      m.X1[i] = now[i];
      m.X2[i] = now[N + i];
      m.a[i] = now[2 * N + i];
    }
  }
  // Lanes that restart (not `keep`) from X(0) restart their sensors there: the last rate and the
  // delayed measurements X(0), the low-pass 0 (so no spike from a rate of 0 before X2(0)).
  void reset_sensors(const Mask& keep) {
    for (int i = 0; i < N; ++i) {
      rate_prev_[i] = lane::select(keep, rate_prev_[i], x0_[N + i]);
      lowpass_[i] = lane::select(keep, lowpass_[i], T(0.0));
    }
    if (delay_ == 0) return;
    for (int slot = 0; slot <= delay_; ++slot)
      for (int r = 0; r < 3 * N; ++r) {
        double* p = su_.ring + (static_cast<std::size_t>(slot) * 3 * N + r) * kMaxLanes;
        const T start = r < 2 * N ? x0_[r] : T(0.0);
        lane::store(lane::select(keep, lane::load_lanes<T>(p), start), p);
      }
  }

  // The actuator model's update over a half step, u_a ← u_a + clamp((u_c − u_a)·gain,
  // ±max_step) (ftc/sim/scenario.hpp's ActuatorSteps), towards the command u_c.
  FTC_HOT_INLINE VM lag(const VM& from, const VM& uc) const {
    VM to;
    for (int j = 0; j < M; ++j) {
      T d = (uc[j] - from[j]) * act_gain_;
      d = lane::select(d > act_step_, act_step_, d);
      d = lane::select(d < act_neg_, act_neg_, d);
      to[j] = from[j] + d;
    }
    return to;
  }

  // The substeps of one sample, compiled twice: with the actuator model (A), and without it
  // exactly as before it existed (no test or copy in the loop of a run without one). f: f(X) at
  // the sample's state, known from the acceleration sensor.
  template <bool A>
  FTC_HOT_INLINE void substeps(const double* e, const VN& f, const VM& u, SampleLanes<N, M>& o) {
    [[maybe_unused]] VM uc;  // the command within the actuator's range
    if constexpr (A)
      for (int r = 0; r < M; ++r) {
        lane::store(ua_[r], o.ua[r]);
        const T c = lane::select(u[r] < limit_lo_[r], limit_lo_[r], u[r]);
        uc[r] = lane::select(c > limit_hi_[r], limit_hi_[r], c);
      }
    // Stage 1 of the first substep is at (t, X): f(X) and the inputs are already known.
    const VN a1 = accel(f, forcing(e, A ? ua_ : u));
    VS k1;
    for (int r = 0; r < N; ++r) {
      k1[r] = x_[N + r];
      k1[N + r] = a1[r];
    }
    const T hv(hv_), h2(h2_), h6(h6_);
    for (int j = 0; j < S_; ++j) {
      const double* ej = e + j * 3 * kInstant;
      if constexpr (A) {
        if (j > 0) k1 = deriv(x_, forcing(ej, ua_));
        const VM ua_mid = lag(ua_, uc);
        const VM ua_end = lag(ua_mid, uc);
        const Forcing mid = forcing(ej + kInstant, ua_mid);
        const Forcing end = forcing(ej + 2 * kInstant, ua_end);
        sim::rk4_advance(
            x_, k1, h2, hv, h6, [&](const VS& s) FTC_HOT_LAMBDA { return deriv(s, mid); },
            [&](const VS& s) FTC_HOT_LAMBDA { return deriv(s, end); });
        ua_ = ua_end;
      } else {
        if (j > 0) k1 = deriv(x_, forcing(ej, u));
        const Forcing mid = forcing(ej + kInstant, u);
        const Forcing end = forcing(ej + 2 * kInstant, u);
        sim::rk4_advance(
            x_, k1, h2, hv, h6, [&](const VS& s) FTC_HOT_LAMBDA { return deriv(s, mid); },
            [&](const VS& s) FTC_HOT_LAMBDA { return deriv(s, end); });
      }
    }
  }

  const PackSetup<N, M>& su_;
  Plant& plant_;
  Plant sensed_;  // with sensors: the plant's lane code at the measured state
  Law& law_;
  MetricLanes<T, N, M>& metrics_;
  std::array<T, M> u0_;  // kTrimmed: the operating point
  std::array<T, M> limit_lo_, limit_hi_;  // the command's limits (MetricSetup's)
  T G_[N * M];  // kConstantInput
  const double Ts_, hv_, h2_, h6_;
  const int S_;
  const bool act_;
  const T act_gain_, act_step_, act_neg_;
  const bool sensors_;
  const int delay_;
  const bool differentiated_;
  const T angle_step_, rate_step_, lowpass_gain_;
  VN rate_prev_, lowpass_;  // differentiated: X2m_{k-1} and y_{k-1}
  VS x0_, x_;
  VM u_prev_, ua_;
  bool live_[W];  // lanes still counting
  int live_count_ = 0;
  Mask counting_;
  std::int64_t samples_[W];
  bool diverged_[W];
  double diverged_at_[W];
  double x_end_[S2][W];
};

// The loop: every sample of the pack through ClosedLoop::step, the inputs fetched and the
// samples handed to the host a block at a time; the pack ends when every lane has diverged or
// all samples are done.
template <class T, bool SharedInputs, class MakePlant, class MakeLaw, int N, int M>
void run_closed_loop(const PackSetup<N, M>& su, MakePlant&& make_plant, MakeLaw&& make_law,
                     PackHost<N, M>& host, PackFinal<N, M>& fin) {
  using Plant = decltype(make_plant());
  using Law = decltype(make_law());
  using Loop = ClosedLoop<T, Plant, Law, SharedInputs, N, M>;
  Plant plant = make_plant();
  Law law = make_law();
  MetricLanes<T, N, M> metrics(su.metrics);
  Loop loop(su, plant, law, metrics);
  const int stride = Loop::sample_stride(su.substeps);
  SampleLanes<N, M> out[32];
  const int block = su.block < 32 ? su.block : 32;
  // A sample's measurement noise: 3N rows of the inputs' stride.
  const int noise_stride = 3 * N * ExoRows<N, M>::stride(SharedInputs, lane::kWidth<T>);
  std::int64_t k = 0;
  while (k < su.samples && loop.running()) {
    const int n = static_cast<int>(su.samples - k < block ? su.samples - k : block);
    const double* exo = host.inputs(k, n);
    const double* noise = su.sensors ? host.noise(k, n) : nullptr;
    for (int i = 0; i < n; ++i, ++k)
      loop.step(k, exo + i * stride, noise ? noise + i * noise_stride : nullptr, out[i]);
    if (su.want_samples) host.samples(k - n, n, out);
  }
  loop.finish(fin);
}

// The pack with the law of its controller type (chosen once per pack) and the kind of inputs.
template <class T, class P, int N, int M>
void run_pack(const PackSetup<N, M>& su, PackHost<N, M>& host, PackFinal<N, M>& fin) {
  using Plant = typename PlantLanes<P>::template Lanes<T>;
  const auto make_plant = [&] { return Plant(su); };
  const ControllerConfig* configs[lane::kWidth<T>];
  for (int l = 0; l < lane::kWidth<T>; ++l) configs[l] = su.configs[l < su.lanes ? l : 0];
  visit_controller_type(su.configs[0]->type, [&](auto t) {
    using Law = typename law::LawOf<decltype(t)::value>::template type<T, N, M>;
    const auto make_law = [&] { return Law(configs, su.Ts); };
    if (su.shared_inputs)
      run_closed_loop<T, true>(su, make_plant, make_law, host, fin);
    else
      run_closed_loop<T, false>(su, make_plant, make_law, host, fin);
  });
}

// A runtime Controller as the law of one lane (T = double): the loop hands it the sample's time
// and measurements, and f(X) of the simulated plant (a controller whose model is that plant
// reuses it), through the host's ObjectController.
template <int N, int M>
class ObjectLaw {
 public:
  explicit ObjectLaw(const ObjectController& c) : c_(c) { c_.reset(c_.self); }
  void reset_lanes(bool keep) {
    if (!keep) c_.reset(c_.self);
  }
  template <class GP>
  FTC_HOT_INLINE void step(const law::Sample<double, N>& m, const GP*, law::V<double, M>& u) {
    c_.step(c_.self, m.t, m.X1.data(), m.X2.data(), m.a.data(), m.f.data(), u.data());
  }

 private:
  ObjectController c_;
};

// A plant seen only through the Plant<n, m> interface, as lane code of one lane (T = double):
// f(X) and G(X) through the host's ObjectPlant, G u summed G(i,0) u0 + G(i,1) u1 + ... as the
// loop sums a constant G. G⁺ is the controller's own business (ObjectLaw ignores it).
template <int N, int M>
class ObjectPlantLanes {
 public:
  static constexpr bool kTrimmed = false;
  static constexpr bool kConstantInput = false;

  explicit ObjectPlantLanes(const ObjectPlant& p) : p_(p) {}
  FTC_HOT_INLINE void drift(const std::array<double, 2 * N>& x, std::array<double, N>& f,
                            std::array<double, N>* f_model) {
    p_.f(p_.self, x.data(), f.data());
    if (f_model) *f_model = f;
    x_ = x;
  }
  FTC_HOT_INLINE void input(const std::array<double, M>& u, std::array<double, N>& Gu) const {
    double G[N * M];
    p_.G(p_.self, x_.data(), G);
    for (int i = 0; i < N; ++i) {
      double g = G[i * M] * u[0];
      for (int j = 1; j < M; ++j) g = g + G[i * M + j] * u[j];
      Gu[i] = g;
    }
  }
  FTC_HOT_INLINE void pinv(const std::array<double, 2 * N>&, double* out) const {
    for (int i = 0; i < M * N; ++i) out[i] = 0.0;
  }

 private:
  ObjectPlant p_;
  std::array<double, 2 * N> x_{};  // the state of the last drift()
};

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

// Defined only in the scalar copy of a plant's kernel file (FTC_KERNEL_COPY: sim_core/
// CMakeLists.txt), where PlantLanes<P> is complete; elsewhere it is only called.
#if defined(FTC_KERNEL_COPY) && !defined(FTC_LANE_ARCH)
namespace isa_scalar {
template <class P, int N, int M>
void controller_kernel(const PackSetup<N, M>& su, PackHost<N, M>& host, PackFinal<N, M>& fin,
                       const ObjectController& c) {
  using Plant = typename PlantLanes<P>::template Lanes<double>;
  run_closed_loop<double, true>(
      su, [&] { return Plant(su); }, [&] { return ObjectLaw<N, M>(c); }, host, fin);
}
}  // namespace isa_scalar
#endif

inline namespace FTC_ISA_NS {}  // namespace FTC_ISA_NS
}  // namespace ftc::sim::detail

// In a plant's lanes file, after its PlantLanes<P>: the kernel of P for the instruction set the
// file is compiled for (lanes/pack.hpp declares one per instruction set), and in the scalar copy
// the loop of P with a runtime Controller (controller_kernel).
#define FTC_PLANT_KERNEL(P)                                                                      \
  FTC_PLANT_CONTROLLER_KERNEL(P)                                                                 \
  template void ftc::sim::detail::FTC_ISA_NS::pack_kernel<P, ftc::sim::detail::PlantLanes<P>::N, \
                                                          ftc::sim::detail::PlantLanes<P>::M>(   \
      const ftc::sim::detail::PackSetup<ftc::sim::detail::PlantLanes<P>::N,                      \
                                        ftc::sim::detail::PlantLanes<P>::M>&,                    \
      ftc::sim::detail::PackHost<ftc::sim::detail::PlantLanes<P>::N,                             \
                                 ftc::sim::detail::PlantLanes<P>::M>&,                           \
      ftc::sim::detail::PackFinal<ftc::sim::detail::PlantLanes<P>::N,                            \
                                  ftc::sim::detail::PlantLanes<P>::M>&);

#if defined(FTC_LANE_ARCH)
#define FTC_PLANT_CONTROLLER_KERNEL(P)
#else
#define FTC_PLANT_CONTROLLER_KERNEL(P)                                            \
  template void ftc::sim::detail::isa_scalar::controller_kernel<                  \
      P, ftc::sim::detail::PlantLanes<P>::N, ftc::sim::detail::PlantLanes<P>::M>( \
      const ftc::sim::detail::PackSetup<ftc::sim::detail::PlantLanes<P>::N,       \
                                        ftc::sim::detail::PlantLanes<P>::M>&,     \
      ftc::sim::detail::PackHost<ftc::sim::detail::PlantLanes<P>::N,              \
                                 ftc::sim::detail::PlantLanes<P>::M>&,            \
      ftc::sim::detail::PackFinal<ftc::sim::detail::PlantLanes<P>::N,             \
                                  ftc::sim::detail::PlantLanes<P>::M>&,           \
      const ftc::sim::detail::ObjectController&);
#endif
