#pragma once
// The closed loop of SPEC §4 for a Controller object (the runtime's sim::simulate(plant,
// controller, ...), registry.cpp), compiled per plant class so that its f and G inline into it;
// the controller is called through its interface. It runs the operations of the batch kernel
// (lanes/closed_loop.hpp), which AnyPlant's simulations run, so that a runtime controller
// replays a tuning run's lane to the last bit (tests/test_batch_kernel.cpp). Also the host
// side's pieces the kernels share: the exogenous inputs and the recorded rows. Private to
// sim_core.
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <type_traits>
#include <vector>

#include "ftc/sim/disturbance.hpp"
#include "ftc/sim/faults.hpp"
#include "ftc/sim/integrator.hpp"
#include "ftc/sim/simulation.hpp"
#include "metrics_accumulator.hpp"
#include "sincos.hpp"

namespace ftc::sim::detail {

// Δ(t) and the fault effect depend on time only, and RK4 asks for them on the grid of half
// steps t_k, t_k + h/2, t_k + h, ... (the midpoint serves two stages, the end of a step is the
// next step's start). They are filled a block of Phasor::kMaxSteps half steps at a time: the
// sinusoids advance along the grid by rotation from an anchor (lanes/elementary.hpp) at the block's
// first instant, into one table per sinusoid, and Disturbance::evaluate and FaultSet::evaluate then
// run each term over the whole block. Term by term over a block is a few instructions per instant,
// where one instant at a time spent about 300 on bookkeeping. The block is of fixed size, so
// memory does not grow with the duration.
template <int N, int M>
class ExogenousInputs {
 public:
  struct Entry {
    Vec<N> disturbance = Vec<N>::Zero();
    FaultEffect<M> fault;
  };

  ExogenousInputs(const Disturbance& d, const FaultSet& f, double sample_time, int substeps)
      : dist_(d),
        faults_(f),
        Ts_(sample_time),
        h_(sample_time / substeps),
        substeps_(substeps),
        phasors_(phasors_of(d.terms(), 0.5 * h_)),
        n_dist_(phasors_.size()) {
    for (const Phasor& p : phasors_of(f.faults(), 0.5 * h_)) phasors_.push_back(p);
    sin_.resize(phasors_.size() * kInstants);
    cos_.resize(phasors_.size() * kInstants);
    // Only a bias fault reads its cosine (FaultSet::evaluate), and only from its onset on.
    for (std::size_t i = 0; i < f.faults().size(); ++i)
      if (f.faults()[i].type == FaultType::bias) bias_.push_back(i);
    active_.reserve(phasors_.size());  // the loop allocates nothing
  }

  // The inputs at the start, midpoint and end of substep j of sample k: three consecutive
  // entries. Steps must be asked for in order, each once.
  const Entry* step(std::int64_t k, int j) {
    if (used_ == kSteps) {
      fill(k, j);
      used_ = 0;
    }
    return &entries_[2 * used_++];
  }

 private:
  static constexpr int kSteps = Phasor::kMaxSteps / 2;  // RK4 steps per block
  static constexpr int kInstants = 2 * kSteps + 1;      // half-step instants per block

  // The instants of the block's steps from substep j of sample k on: each step's start
  // k·Ts + j·h, midpoint and end, the end of a sample's last substep formed as (k+1)·Ts so that
  // it is the very double at which the next sample starts.
  void fill(std::int64_t k, int j) {
    for (int s = 0; s < kSteps; ++s) {
      const double t = static_cast<double>(k) * Ts_;
      const double tj = t + j * h_;
      if (s == 0) t_[0] = tj;
      t_[2 * s + 1] = tj + 0.5 * h_;
      t_[2 * s + 2] = j == substeps_ - 1 ? static_cast<double>(k + 1) * Ts_ : tj + h_;
      if (++j == substeps_) {
        j = 0;
        ++k;
      }
    }
    // The phasors whose values the block reads: every disturbance term's, and a bias fault's
    // once the block reaches its onset (before it, ρ = 0 and FaultSet::evaluate reads no
    // cosine; t < onset for every instant of the block when it holds for the last one). Each
    // phasor is anchored at the block's first instant, so a table left out changes no other.
    active_.clear();
    for (std::size_t i = 0; i < n_dist_; ++i) active_.push_back(i);
    for (const std::size_t i : bias_)
      if (!(t_[kInstants - 1] < faults_.faults()[i].onset)) active_.push_back(n_dist_ + i);
    std::size_t first = 0;
    for (; first + 4 <= active_.size(); first += 4) tabulate<4>(first);
    for (; first + 2 <= active_.size(); first += 2) tabulate<2>(first);
    if (first < active_.size()) tabulate<1>(first);

    dist_.evaluate(
        kInstants,
        [&](std::size_t i, std::size_t n, Shape shape) {
          return (shape == Shape::sin ? sin_ : cos_)[i * kInstants + n];
        },
        [&](std::size_t n) -> Vec<N>& { return entries_[n].disturbance; });
    faults_.evaluate(
        t_, [&](std::size_t i, std::size_t n) { return cos_[(n_dist_ + i) * kInstants + n]; },
        [&](std::size_t n) -> FaultEffect<M>& { return entries_[n].fault; });
  }

  // The phasors active_[a .. a + G - 1] over the block. Local copies keep each rotation in
  // registers, and a group advances together so that the CPU overlaps their dependency chains.
  template <int G>
  void tabulate(std::size_t a) {
    std::array<Phasor, G> q;
    double* sin_of[G];
    double* cos_of[G];
    for (int g = 0; g < G; ++g) {
      const std::size_t i = active_[a + g];
      q[g] = phasors_[i];
      q[g].anchor(t_[0]);
      sin_of[g] = &sin_[i * kInstants];
      cos_of[g] = &cos_[i * kInstants];
    }
    for (int n = 0; n < kInstants; ++n)
      for (int g = 0; g < G; ++g) {
        if (n > 0) q[g].advance();
        sin_of[g][n] = q[g].sin();
        cos_of[g][n] = q[g].cos();
      }
  }

  const Disturbance& dist_;
  const FaultSet& faults_;
  double Ts_, h_;
  int substeps_;
  std::vector<Phasor> phasors_;  // the disturbance terms', then the faults'; sized once
  std::size_t n_dist_;
  std::vector<double> sin_, cos_;  // per phasor, its values at the block's instants
  std::vector<std::size_t> bias_;    // the bias faults' indices
  std::vector<std::size_t> active_;  // the phasors tabulated for the current block
  std::array<double, kInstants> t_{};
  std::array<Entry, kInstants> entries_;
  int used_ = kSteps;  // steps of the current block handed out
};

template <int S>
bool out_of_bounds(const Vec<S>& x) {
  for (int i = 0; i < S; ++i)
    if (!(std::abs(x[i]) <= kDivergenceBound)) return true;  // also catches NaN
  return false;
}

// The plant's scratch space for f at nearby states, when it has one (Spacecraft::Workspace).
struct NoWorkspace {};
template <class P>
auto make_workspace() {
  if constexpr (requires { typename P::Workspace; })
    return typename P::Workspace{};
  else
    return NoWorkspace{};
}

template <class P, class W>
FTC_HOT_INLINE typename P::Vector drift(const P& plant, const typename P::State& x, W& ws) {
  if constexpr (std::is_same_v<W, NoWorkspace>)
    return plant.f(x);
  else
    return plant.f(x, ws);
}

// G(X), from the workspace's sines and cosines when the plant has a G for it
// (Manipulator::G(x, ws)): those f(x, ws) used at the same X.
template <class P, class W>
FTC_HOT_INLINE typename P::InputMatrix input_matrix(const P& plant, const typename P::State& x,
                                                    W& ws) {
  if constexpr (requires { plant.G(x, ws); })
    return plant.G(x, ws);
  else
    return plant.G(x);
}

// The command after the faults, the saturation and the limits for a plant whose actuators work
// about an operating point (actuator_trim(), as Hexarotor's): the faults act on u0 + u_d. The
// operations of the batch kernel's (lanes/closed_loop.hpp).
template <class P>
concept TrimmedPlant = requires(const P& p) { p.actuator_trim(); };

template <int M, class Trim>
FTC_HOT_INLINE Vec<M> apply_trimmed(const Trim& t, const FaultSet& faults,
                                    const FaultEffect<M>& e, const Vec<M>& u_d) {
  const double m = faults.saturation().value_or(std::numeric_limits<double>::infinity());
  Vec<M> u;
  for (int j = 0; j < M; ++j) {
    double v = (e.gain[j] * (t.u0[j] + u_d[j]) + e.offset[j]) - t.u0[j];
    v = v < -m ? -m : v;
    v = v > m ? m : v;
    v = v < t.lo[j] ? t.lo[j] : v;
    u[j] = v > t.hi[j] ? t.hi[j] : v;
  }
  return u;
}

// One recorded sample; out of line, as it is rare and would bloat the loop.
template <int N, int M>
[[gnu::noinline]] void append_row(Trajectory& tr, double t, const StateOf<N>& x, const Vec<M>& u_d,
                                  const Vec<M>& u) {
  std::vector<double>& v = tr.values;
  v.push_back(t);
  v.insert(v.end(), x.data(), x.data() + 2 * N);
  v.insert(v.end(), u_d.data(), u_d.data() + M);
  v.insert(v.end(), u.data(), u.data() + M);
}

// The loop for plant class P and controller type C (the Controller<n, m> interface in practice):
// for a final plant class the calls to f and G are devirtualised and inlined.
template <class P, class C>
SimulationResult run(const P& plant, C& controller, const Scenario& scenario,
                     const SimulationOptions& options) {
  constexpr int N = P::kAxes, M = P::kActuators;
  using StateT = typename P::State;
  using Entry = typename ExogenousInputs<N, M>::Entry;
  const Disturbance disturbance(scenario.disturbance);
  const FaultSet faults(scenario.faults, scenario.saturation);

  std::vector<double> onsets;
  onsets.reserve(scenario.faults.size());
  for (const Fault& f : scenario.faults) onsets.push_back(f.onset);
  MetricContext<M> context;
  context.duration = scenario.duration;
  context.settings = options.metrics;
  {
    constexpr double inf = std::numeric_limits<double>::infinity();
    const double u_max = scenario.saturation.value_or(inf);
    for (int j = 0; j < M; ++j) {
      CommandLimits c = command_limits(u_max, -inf, inf);
      if constexpr (TrimmedPlant<P>)
        c = command_limits(u_max, plant.actuator_trim().lo[j], plant.actuator_trim().hi[j]);
      context.lo[j] = c.lo;
      context.hi[j] = c.hi;
    }
  }
  MetricsAccumulator<N, M> metrics(scenario.sample_time, options.window, options.extra_windows,
                                   std::move(onsets), context);

  const double Ts = scenario.sample_time;
  const double h = Ts / scenario.substeps;
  ExogenousInputs<N, M> exo(disturbance, faults, Ts, scenario.substeps);
  const std::int64_t Nk = scenario.samples();

  SimulationResult result;
  result.trajectory.axes = N;
  result.trajectory.actuators = M;
  if (options.record_every > 0)
    result.trajectory.values.reserve((Nk / options.record_every + 1) * result.trajectory.width());

  controller.reset();
  const StateT x0 = Eigen::Map<const StateT>(scenario.initial_state.data());
  StateT x = x0;
  Vec<M> u_prev = Vec<M>::Zero();

  const bool constant_G = plant.input_matrix_is_constant();
  const Mat<N, M> G0 = plant.G(x0);
  auto ws = make_workspace<P>();
  // dX2/dt = f(X) + G(X) u + Δ(t), with u the command u_d after the faults of time t.
  const auto applied = [&](const FaultEffect<M>& fe, const Vec<M>& u_d) FTC_HOT_LAMBDA {
    if constexpr (TrimmedPlant<P>)
      return apply_trimmed<M>(plant.actuator_trim(), faults, fe, u_d);
    else
      return faults.apply(fe, u_d);
  };
  const auto accel = [&](const StateT& s, const Vec<N>& fs, const Entry& e, const Vec<M>& u_d)
                         FTC_HOT_LAMBDA -> Vec<N> {
    const Vec<M> u = applied(e.fault, u_d);
    // Summed in the order the batch kernels sum (lanes/closed_loop.hpp), so that a
    // Controller simulated here issues the commands of a tuning run's lane to the last bit.
    const auto row_times_u = [&](const Mat<N, M>& G, int i) FTC_HOT_LAMBDA {
      double g = G(i, 0) * u[0];
      for (int j = 1; j < M; ++j) g = g + G(i, j) * u[j];
      return g;
    };
    Vec<N> a;
    if (constant_G) {
      for (int i = 0; i < N; ++i) a[i] = (fs[i] + row_times_u(G0, i)) + e.disturbance[i];
    } else {
      const Mat<N, M> G = input_matrix(plant, s, ws);
      for (int i = 0; i < N; ++i) a[i] = (fs[i] + row_times_u(G, i)) + e.disturbance[i];
    }
    return a;
  };
  // dX/dt at state s and stage inputs e, with the plant's input v: the command of this sample
  // held, or the actuators' output at the stage's instant.
  const auto deriv = [&](const StateT& s, const Entry& e, const Vec<M>& v) FTC_HOT_LAMBDA
      -> StateT {
    StateT d;
    d.template head<N>() = s.template tail<N>();
    d.template tail<N>() = accel(s, drift(plant, s, ws), e, v);
    return d;
  };

  // The actuator model (docs/model.md): its output u_a (0 at t = 0) follows the command clamped
  // to the actuator's range, stepped over each half step as the kernel steps it.
  const bool act = scenario.actuator.has_value();
  const ActuatorSteps act_steps =
      act ? actuator_steps(*scenario.actuator, 0.5 * h) : ActuatorSteps{};
  Vec<M> ua = Vec<M>::Zero();
  const auto lag = [&](const Vec<M>& from, const Vec<M>& uc) FTC_HOT_LAMBDA {
    const double g = act_steps.gain, s = act_steps.max_step, neg = -s;
    Vec<M> to;
    for (int j = 0; j < M; ++j) {
      double d = (uc[j] - from[j]) * g;
      d = d > s ? s : d;
      d = d < neg ? neg : d;
      to[j] = from[j] + d;
    }
    return to;
  };

  std::int64_t k = 0;
  for (; k < Nk; ++k) {
    const double t = static_cast<double>(k) * Ts;
    const Vec<N> fx = drift(plant, x, ws);
    const Entry* e = exo.step(k, 0);  // at the start, midpoint, end
    const Vec<N> a = accel(x, fx, e[0], act ? ua : u_prev);

    const Vec<M> u =
        controller.step(Measurement<N>{t, x.template head<N>(), x.template tail<N>(), a, &fx,
                                       static_cast<const Plant<N, M>*>(&plant)});
    metrics.sample(t, x, u);
    if (options.record_every > 0 && k % options.record_every == 0)
      append_row<N, M>(result.trajectory, t, x, u, applied(e[0].fault, act ? ua : u));

    Vec<M> uc = u;  // the command within the actuator's range
    if (act)
      for (int j = 0; j < M; ++j) {
        const double c = u[j] < context.lo[j] ? context.lo[j] : u[j];
        uc[j] = c > context.hi[j] ? context.hi[j] : c;
      }
    // Stage 1 of the first substep is at (t, X): f(X) and Δ(t) are already known.
    StateT k1;
    k1.template head<N>() = x.template tail<N>();
    k1.template tail<N>() = accel(x, fx, e[0], act ? ua : u);
    // The last stage of the sample ends at t_{k+1} = (k+1)·Ts, the very instant (bit for bit)
    // at which the next sample's sensor reads; ExogenousInputs forms the instants likewise.
    const int S = scenario.substeps;
    for (int j = 0; j < S; ++j) {
      if (j > 0) {
        e = exo.step(k, j);
        k1 = deriv(x, e[0], act ? ua : u);
      }
      const Entry& em = e[1];
      const Entry& ee = e[2];
      Vec<M> ua_mid = ua, ua_end = ua;
      if (act) {
        ua_mid = lag(ua, uc);
        ua_end = lag(ua_mid, uc);
      }
      const Vec<M>& vm = act ? ua_mid : u;
      const Vec<M>& ve = act ? ua_end : u;
      x = rk4_step(
          x, h, k1, [&](const StateT& s) FTC_HOT_LAMBDA { return deriv(s, em, vm); },
          [&](const StateT& s) FTC_HOT_LAMBDA { return deriv(s, ee, ve); });
      if (act) ua = ua_end;
    }
    u_prev = u;

    if (out_of_bounds(x)) {
      metrics.mark_diverged(t + Ts);
      ++k;
      break;
    }
  }
  result.samples = k;
  result.final_state.assign(x.data(), x.data() + 2 * N);
  result.metrics = metrics.result();
  return result;
}

}  // namespace ftc::sim::detail
