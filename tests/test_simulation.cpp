#include <gtest/gtest.h>

#include <cmath>
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
// instants, several substeps and saturation must agree to rounding.
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
