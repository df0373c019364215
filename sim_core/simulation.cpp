#include "ftc/sim/simulation.hpp"

#include <array>
#include <cmath>

#include "ftc/sim/integrator.hpp"
#include "ftc/sim/spacecraft.hpp"

namespace ftc::sim {
namespace {

// Δ(t) and the fault effect depend on time only. RK4 asks for them at t, t + h/2 (twice) and
// t + h, and the acceleration sensor at t again, so a few remembered instants remove most of
// the trigonometry from the loop.
class ExogenousCache {
 public:
  struct Entry {
    double t = std::numeric_limits<double>::quiet_NaN();
    Vec3 disturbance = Vec3::Zero();
    FaultEffect fault;
  };

  ExogenousCache(const Disturbance& d, const FaultSet& f)
      : dist_(d), faults_(f), dist_trig_(d.terms().size()), fault_trig_(f.faults().size()) {}

  const Entry& at(double t) {
    for (const Entry& e : slots_)
      if (e.t == t) return e;
    Entry& e = slots_[next_];
    next_ = (next_ + 1) % slots_.size();
    e.t = t;
    e.disturbance = dist_(t, dist_trig_);
    e.fault = faults_.effect(t, fault_trig_);
    return e;
  }

 private:
  const Disturbance& dist_;
  const FaultSet& faults_;
  std::vector<SinCosTracker> dist_trig_, fault_trig_;  // sized once, before the loop
  std::array<Entry, 3> slots_{};
  std::size_t next_ = 0;
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
  ExogenousCache exo(disturbance, faults);

  std::vector<double> onsets;
  onsets.reserve(scenario.faults.size());
  for (const Fault& f : scenario.faults) onsets.push_back(f.onset);
  MetricsAccumulator metrics(scenario.sample_time, options.window, options.extra_windows,
                             std::move(onsets));

  const double Ts = scenario.sample_time;
  const double h = Ts / scenario.substeps;
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
  const auto accel = [&](const State& s, const Vec3& fs, const ExogenousCache::Entry& e,
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
  const auto deriv = [&](const State& s, const ExogenousCache::Entry& e) -> State {
    State d;
    d.head<kAxes>() = s.tail<kAxes>();
    d.tail<kAxes>() = accel(s, plant.f(s, ws), e, u_held);
    return d;
  };

  std::int64_t k = 0;
  for (; k < N; ++k) {
    const double t = static_cast<double>(k) * Ts;
    const Vec3 fx = plant.f(x, ws);
    const ExogenousCache::Entry& e0 = exo.at(t);
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
      if (j > 0) k1 = deriv(x, exo.at(tj));
      const ExogenousCache::Entry& em = exo.at(tj + 0.5 * h);
      const ExogenousCache::Entry& ee = exo.at(j == S - 1 ? t_next : tj + h);
      x = rk4_step(
          x, h, k1, [&](const State& s) { return deriv(s, em); },
          [&](const State& s) { return deriv(s, ee); });
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
