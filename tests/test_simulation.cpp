#include <gtest/gtest.h>

#include <cmath>
#include <optional>
#include <span>
#include <vector>

#include "constant_command.hpp"
#include "ftc/sim/controller.hpp"
#include "ftc/sim/disturbance.hpp"
#include "ftc/sim/faults.hpp"
#include "ftc/sim/integrator.hpp"
#include "ftc/sim/simulation.hpp"
#include "ftc/sim/spacecraft.hpp"
#include "plants/spacecraft_dynamics.hpp"

using namespace ftc::sim;
using namespace ftc::testing;

// The simulator fills the disturbance and the fault effects a block of half steps at a time,
// from sinusoids advanced by rotation. Against a plain RK4 that evaluates Δ(t) and the faults
// with libm at every stage, an open-loop run with every kind of fault, onsets between grid
// instants, several substeps and saturation must agree to rounding. The bias starts inside a
// block of half steps, whose cosine is the first the simulator tabulates (none before its
// onset): tabulating from the next block on instead fails here (checked), while the lanes-versus-
// scalar tests, sharing the tables, would not see it.
TEST(Simulation, ExogenousInputsFollowTheirDefinitions) {
  const Spacecraft plant;
  Scenario s = Scenario::paper();
  s.duration = 3.0;
  s.sample_time = 0.05;
  s.substeps = 3;  // 180 RK4 steps: eleven blocks and part of a twelfth
  s.initial_state = {0.3, -0.2, 0.5, 0.4, -0.6, 0.2};
  s.disturbance = {{1, Shape::sin, 0.5, 1.0, 0.0},
                   {2, Shape::cos, 0.5, 2.0, 0.0},
                   {2, Shape::sin, 0.2, 7.0, 0.4},
                   {3, Shape::sin, 0.5, 3.0, -1.0}};
  Fault bias;
  bias.actuator = 1;
  bias.type = FaultType::bias;
  bias.onset = 0.2371;
  bias.profile = {FaultProfileType::incipient, 3.0};
  bias.offset = 0.5;
  bias.amplitude = 1.5;
  bias.frequency = 4.0;
  bias.phase = 0.2;
  Fault loe;
  loe.actuator = 2;
  loe.type = FaultType::loss_of_effectiveness;
  loe.onset = 0.5003;
  loe.fraction = 0.6;
  Fault stuck;
  stuck.actuator = 3;
  stuck.type = FaultType::stuck;
  stuck.onset = 1.3007;
  stuck.value = 2.5;
  s.faults = {bias, loe, stuck};
  s.saturation = 1.8;
  const Vec4 command(0.1, -0.2, 0.05, 0.1);
  ConstantCommand c(command);
  SimulationOptions o;
  o.record_every = 1;
  const SimulationResult r = simulate(plant, c, s, o);

  const Disturbance d(s.disturbance);
  const FaultSet faults(s.faults, s.saturation);
  const State x0 = state_of(s.initial_state);
  const Mat34 G = plant.G(x0);
  const auto deriv = [&](double t, const State& x) {
    State dx;
    dx.head<3>() = x.tail<3>();
    dx.tail<3>() = plant.f(x) + G * faults.apply(t, command) + d.at<3>(t);
    return dx;
  };
  State x = x0;
  const double h = s.sample_time / s.substeps;
  for (std::int64_t k = 0; k < s.samples(); ++k) {
    const double t = static_cast<double>(k) * s.sample_time;
    // The applied inputs recorded at each sample are the faults' definition at that instant.
    ASSERT_TRUE(input_of(r.trajectory.u(k)).isApprox(faults.apply(t, command), 1e-13)) << t;
    for (int j = 0; j < s.substeps; ++j) x = rk4_step(x, t + j * h, h, deriv);
  }
  EXPECT_TRUE(state_of(r.final_state).isApprox(x, 1e-12))
      << (state_of(r.final_state) - x).transpose();
  EXPECT_GT((x - x0).norm(), 0.1);  // the run went somewhere
}

TEST(Simulation, StopsAndMarksDivergence) {
  const Spacecraft plant;
  Scenario s = Scenario::paper();
  s.duration = 5.0;
  ConstantCommand c(Vec4(1e5, 1e5, 1e5, 1e5));
  const SimulationResult r = simulate(plant, c, s);
  EXPECT_TRUE(r.metrics.diverged);
  EXPECT_LT(r.samples, s.samples());
  EXPECT_TRUE(std::isinf(r.metrics.errors.ise));
  EXPECT_GT(r.metrics.diverged_at, 0.0);
}

TEST(Simulation, RecordsDecimatedTrajectory) {
  const Spacecraft plant;
  Scenario s = Scenario::paper();
  s.duration = 1.0;
  ConstantCommand c(Vec4::Zero());
  SimulationOptions o;
  o.record_every = 10;
  const SimulationResult r = simulate(plant, c, s, o);
  ASSERT_EQ(r.trajectory.rows(), 100u);
  const std::span<const double> x0 = r.trajectory.x(0);
  EXPECT_EQ(std::vector<double>(x0.begin(), x0.end()), s.initial_state);
  EXPECT_NEAR(r.trajectory.t(1), 0.01, 1e-15);
  EXPECT_EQ(r.samples, 1000);
}

TEST(Simulation, WindowedMetricsAddUp) {
  const Spacecraft plant;
  Scenario s = Scenario::paper();
  s.duration = 2.0;
  ConstantCommand c(Vec4::Zero());
  SimulationOptions o;
  o.extra_windows = {{0.0, 1.0}, {1.0, 2.0}};
  const Metrics m = simulate(plant, c, s, o).metrics;
  EXPECT_NEAR(m.extra[0].ise + m.extra[1].ise, m.errors.ise, 1e-12 * m.errors.ise);
  EXPECT_NEAR(m.extra[0].itae + m.extra[1].itae, m.errors.itae, 1e-12 * m.errors.itae);
  // ISE by hand over the first sample: Ts ‖X1(0)‖².
  SimulationOptions first;
  first.window = {0.0, 0.0005};
  const Metrics m0 = simulate(plant, c, s, first).metrics;
  const State x0 = state_of(s.initial_state);
  EXPECT_DOUBLE_EQ(m0.errors.ise, 1e-3 * x0.head<3>().squaredNorm());
  EXPECT_DOUBLE_EQ(m0.errors.iae, 1e-3 * x0.head<3>().cwiseAbs().sum());
}

namespace {

// The spacecraft seen only through the Plant interface, and not admitting that G is constant:
// the simulator's generic loop and the controllers' per-sample G⁺ then do the work that the
// built-in spacecraft's specialised paths skip. Its f keeps the spacecraft's angle trackers (one
// simulation at a time), so that both paths evaluate f to the same bits.
class OpaqueSpacecraft final : public Plant<3, 4> {
 public:
  Vec3 f(const State& x) const override { return sc_.f(x, ws_); }
  Mat34 G(const State& x) const override { return sc_.G(x); }
  Mat43 G_pinv(const State& x) const override { return sc_.G_pinv(x); }
  std::string model() const override { return "opaque spacecraft"; }

 private:
  Spacecraft sc_;
  mutable Spacecraft::Workspace ws_;
};

}  // namespace

TEST(Simulation, GenericPlantPathMatchesSpacecraftPath) {
  const Spacecraft fast;
  const OpaqueSpacecraft generic;
  ASSERT_FALSE(generic.input_matrix_is_constant());
  const Scenario s = Scenario::paper();
  for (const ControllerType type : {ControllerType::nftsmc, ControllerType::pi_fosmc,
                                    ControllerType::adaptive_neural_pi_fosmc}) {
    auto c1 = make_controller(ControllerConfig::table1(type), fast, s.sample_time);
    auto c2 = make_controller(ControllerConfig::table1(type), generic, s.sample_time);
    const SimulationResult a = simulate(fast, *c1, s), b = simulate(generic, *c2, s);
    EXPECT_EQ(a.final_state, b.final_state) << to_string(type);
    EXPECT_EQ(a.metrics.errors.ise, b.metrics.errors.ise) << to_string(type);
    EXPECT_EQ(a.metrics.control_tv, b.metrics.control_tv) << to_string(type);
  }
}

namespace {

// An open-loop run of `c` on the spacecraft at rest, every sample recorded: the applied column
// is the actuators' output u_a(t_k) (after the faults), whatever the plant does.
SimulationResult actuator_run(const Vec4& command, const ActuatorModel& model,
                              std::optional<double> saturation = std::nullopt,
                              std::vector<Fault> faults = {}) {
  const Spacecraft plant;
  Scenario s;
  s.name = "actuator";
  s.duration = 0.4;
  s.initial_state = std::vector<double>(6, 0.0);
  s.saturation = saturation;
  s.actuator = model;
  s.faults = std::move(faults);
  ConstantCommand c(command);
  SimulationOptions o;
  o.record_every = 1;
  return simulate(plant, c, s, o);
}

}  // namespace

// The lag alone against its closed form u_a(t) = u_c (1 − e^{−t/τ}) from u_a(0) = 0, with the
// command clamped to the saturation first (actuator 4: 3 → 2.5). The half-step update is the
// exact solution, so only rounding separates them.
TEST(Simulation, ActuatorLagFollowsItsClosedForm) {
  ActuatorModel m;
  m.time_constant = 0.05;
  const Vec4 u(2.0, -1.0, 0.5, 3.0);
  const SimulationResult r = actuator_run(u, m, 2.5);
  ASSERT_EQ(r.trajectory.rows(), 400u);
  const Vec4 uc(2.0, -1.0, 0.5, 2.5);
  for (std::size_t k = 0; k < r.trajectory.rows(); ++k) {
    const double t = r.trajectory.t(k);
    for (int j = 0; j < 4; ++j) {
      EXPECT_EQ(r.trajectory.u_d(k)[j], u[j]);  // the command itself is recorded unclamped
      EXPECT_NEAR(r.trajectory.u(k)[j], uc[j] * (1.0 - std::exp(-t / 0.05)), 1e-13)
          << "t = " << t << ", actuator " << j + 1;
    }
  }
  EXPECT_EQ(r.trajectory.u(0)[0], 0.0);  // at rest at t = 0
  // The metrics price the command (SPEC §16), not the actuator's output.
  EXPECT_EQ(r.metrics.errors.peak_command, 3.0);
}

// With a rate limit R the output ramps at R until the lag asks for less (|u_c − u_a| = R τ),
// then follows the lag: u_c = 3, R = 20/s, τ = 0.05 s ramp to 2 by t = 0.1 s, then
// u_a = 3 − e^{−(t − 0.1)/τ}. Without a lag (actuator 2) the ramp goes all the way: −0.3 at
// −2/s is reached at 0.15 s and held.
TEST(Simulation, ActuatorRateLimitClipsTheSlope) {
  ActuatorModel lag_and_rate;
  lag_and_rate.time_constant = 0.05;
  lag_and_rate.rate_limit = 20.0;
  const SimulationResult r = actuator_run(Vec4(3.0, -3.0, 0.5, 0.0), lag_and_rate);
  ActuatorModel rate_only;
  rate_only.rate_limit = 2.0;
  const SimulationResult q = actuator_run(Vec4(0.0, -0.3, 0.0, 0.0), rate_only);
  for (std::size_t k = 0; k < r.trajectory.rows(); ++k) {
    const double t = r.trajectory.t(k);
    const double up = t <= 0.1 ? 20.0 * t : 3.0 - std::exp(-(t - 0.1) / 0.05);
    EXPECT_NEAR(r.trajectory.u(k)[0], up, 1e-12) << "t = " << t;
    EXPECT_NEAR(r.trajectory.u(k)[1], -up, 1e-12) << "t = " << t;
    // 0.5 is within R τ = 1 of 0: the rate limit never acts, the lag alone.
    EXPECT_NEAR(r.trajectory.u(k)[2], 0.5 * (1.0 - std::exp(-t / 0.05)), 1e-13) << "t = " << t;
    EXPECT_NEAR(q.trajectory.u(k)[1], t <= 0.15 ? -2.0 * t : -0.3, 1e-13) << "t = " << t;
    if (k > 0) {  // never faster than R
      const double dt = t - r.trajectory.t(k - 1);
      EXPECT_LE(std::abs(r.trajectory.u(k)[0] - r.trajectory.u(k - 1)[0]), 20.0 * dt * (1 + 1e-12));
    }
  }
  EXPECT_EQ(q.trajectory.u(q.trajectory.rows() - 1)[1], -0.3);
}

// The faults act on the actuator's output: a stuck actuator holds its value whatever the lag
// does, a loss of effectiveness scales the lagged output.
TEST(Simulation, FaultsActOnTheActuatorsOutput) {
  ActuatorModel m;
  m.time_constant = 0.05;
  Fault stuck;
  stuck.actuator = 1;
  stuck.type = FaultType::stuck;
  stuck.onset = 0.2;
  stuck.value = -0.7;
  Fault loe;
  loe.actuator = 2;
  loe.type = FaultType::loss_of_effectiveness;
  loe.onset = 0.0;
  loe.fraction = 0.25;
  const SimulationResult r = actuator_run(Vec4(1.0, 2.0, 0.0, 0.0), m, std::nullopt, {stuck, loe});
  for (std::size_t k = 0; k < r.trajectory.rows(); ++k) {
    const double t = r.trajectory.t(k), lag = 1.0 - std::exp(-t / 0.05);
    EXPECT_NEAR(r.trajectory.u(k)[0], t >= 0.2 ? -0.7 : lag, 1e-13) << "t = " << t;
    EXPECT_NEAR(r.trajectory.u(k)[1], 0.75 * 2.0 * lag, 1e-13) << "t = " << t;
  }
}
