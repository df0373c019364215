#include "ftc/sim/simulation.hpp"

#include <cmath>

#include "ftc/sim/integrator.hpp"
#include "ftc/sim/spacecraft.hpp"

namespace ftc::sim {
namespace {

// Δ(t) and the fault effect depend on time only, and RK4 asks for them on the grid of half
// steps t_k, t_k + h/2, t_k + h, ... (the midpoint serves two stages, the end of a sample is the
// next sample's sensor instant). Their sinusoids advance along that grid by rotation (Phasor)
// and are re-anchored with libm at the start of a step once Phasor::kMaxSteps half steps have
// passed.
class ExogenousInputs {
 public:
  struct Entry {
    Vec3 disturbance = Vec3::Zero();
    FaultEffect fault;
  };

  ExogenousInputs(const Disturbance& d, const FaultSet& f, double half_step)
      : dist_(d),
        faults_(f),
        dist_phasors_(d.phasors(half_step)),
        fault_phasors_(f.phasors(half_step)) {}

  // The inputs at the start of a step at time t: `last` (the end of the previous step,
  // evaluated at the same t) unless the phasors are due for re-anchoring.
  void start_step(double t, Entry& last) {
    if (steps_ + 2 <= Phasor::kMaxSteps) return;
    for (Phasor& p : dist_phasors_) p.anchor(t);
    for (Phasor& p : fault_phasors_) p.anchor(t);
    steps_ = 0;
    evaluate(t, last);
  }
  // Advances the phasors one half step, to time t, and evaluates there.
  void next(double t, Entry& e) {
    for (Phasor& p : dist_phasors_) p.advance();
    for (Phasor& p : fault_phasors_) p.advance();
    ++steps_;
    evaluate(t, e);
  }

 private:
  void evaluate(double t, Entry& e) const {
    e.disturbance = dist_(dist_phasors_);
    e.fault = faults_.effect(t, fault_phasors_);
  }

  const Disturbance& dist_;
  const FaultSet& faults_;
  std::vector<Phasor> dist_phasors_, fault_phasors_;  // sized once, before the loop
  int steps_ = Phasor::kMaxSteps;                     // advances since the last anchor
};

bool out_of_bounds(const State& x) {
  for (int i = 0; i < kStates; ++i)
    if (!(std::abs(x[i]) <= kDivergenceBound)) return true;  // also catches NaN
  return false;
}

// The loop, compiled once per plant type: for the final Spacecraft class the calls to f are
// devirtualised and inlined, which the four evaluations per sample make worthwhile.
template <class P>
SimulationResult run(const P& plant, Controller& controller, const Scenario& scenario,
                     const SimulationOptions& options) {
  const Disturbance disturbance(scenario.disturbance);
  const FaultSet faults(scenario.faults, scenario.saturation);

  std::vector<double> onsets;
  onsets.reserve(scenario.faults.size());
  for (const Fault& f : scenario.faults) onsets.push_back(f.onset);
  MetricsAccumulator metrics(scenario.sample_time, options.window, options.extra_windows,
                             std::move(onsets));

  const double Ts = scenario.sample_time;
  const double h = Ts / scenario.substeps;
  ExogenousInputs exo(disturbance, faults, 0.5 * h);
  ExogenousInputs::Entry e0, em, ee;  // at the start, midpoint and end of a step
  const std::int64_t N = scenario.samples();

  SimulationResult result;
  if (options.record_every > 0) result.trajectory.reserve(N / options.record_every + 1);

  controller.reset();
  const State x0 = scenario.initial_state;
  State x = x0;
  Vec4 u_prev = Vec4::Zero();
  Vec4 u_held = Vec4::Zero();

  const bool constant_G = plant.input_matrix_is_constant();
  const Mat34 G0 = plant.G(x0);
  // dX2/dt = f(X) + G(X) u + Δ(t), with u the command u_d after the faults of time t.
  const auto accel = [&](const State& s, const Vec3& fs, const ExogenousInputs::Entry& e,
                         const Vec4& u_d) -> Vec3 {
    const Vec4 u = faults.apply(e.fault, u_d);
    Vec3 a = fs;
    if (constant_G)
      a.noalias() += G0 * u;
    else
      a.noalias() += plant.G(s) * u;
    a += e.disturbance;
    return a;
  };
  PlantWorkspace ws;
  // dX/dt at state s and stage inputs e, with the command of this sample held.
  const auto deriv = [&](const State& s, const ExogenousInputs::Entry& e) -> State {
    State d;
    d.head<kAxes>() = s.tail<kAxes>();
    d.tail<kAxes>() = accel(s, plant.f(s, ws), e, u_held);
    return d;
  };

  std::int64_t k = 0;
  for (; k < N; ++k) {
    const double t = static_cast<double>(k) * Ts;
    const Vec3 fx = plant.f(x, ws);
    exo.start_step(t, e0);
    const Vec3 a = accel(x, fx, e0, u_prev);

    const Vec4 u = controller.step(Measurement{t, x.head<kAxes>(), x.tail<kAxes>(), a, &fx});
    metrics.sample(t, x, u);
    if (options.record_every > 0 && k % options.record_every == 0)
      result.trajectory.push_back({t, x, u, faults.apply(e0.fault, u)});

    u_held = u;
    // Stage 1 of the first substep is at (t, X): f(X) and Δ(t) are already known.
    State k1;
    k1.head<kAxes>() = x.tail<kAxes>();
    k1.tail<kAxes>() = accel(x, fx, e0, u);
    // The last stage of the sample ends at t_{k+1} = (k+1)·Ts, the very instant (bit for bit)
    // at which the next sample's sensor reads, so the disturbance and faults there are reused.
    const double t_next = static_cast<double>(k + 1) * Ts;
    const int S = scenario.substeps;
    for (int j = 0; j < S; ++j) {
      const double tj = t + j * h;
      if (j > 0) {
        exo.start_step(tj, e0);
        k1 = deriv(x, e0);
      }
      exo.next(tj + 0.5 * h, em);
      exo.next(j == S - 1 ? t_next : tj + h, ee);
      x = rk4_step(
          x, h, k1, [&](const State& s) { return deriv(s, em); },
          [&](const State& s) { return deriv(s, ee); });
      e0 = ee;
    }
    u_prev = u;

    if (out_of_bounds(x)) {
      metrics.mark_diverged(t + Ts);
      ++k;
      break;
    }
  }
  result.samples = k;
  result.final_state = x;
  result.metrics = metrics.result();
  return result;
}

}  // namespace

SimulationResult simulate(const Plant& plant, Controller& controller, const Scenario& scenario,
                          const SimulationOptions& options) {
  throw_if_errors("scenario " + scenario.name, scenario.validate(""));
  if (const auto* spacecraft = dynamic_cast<const Spacecraft*>(&plant))
    return run(*spacecraft, controller, scenario, options);
  return run(plant, controller, scenario, options);
}

}  // namespace ftc::sim
