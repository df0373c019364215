// The one closed loop (sim_core/lanes/closed_loop.hpp) one step at a time: ClosedLoop::step()
// advances every lane by one sample of SPEC §4 (the acceleration sensor, the law, the metrics,
// RK4), so a caller can drive it sample by sample, with the host's inputs fetched one sample at
// a time, and get the run's bits.
#include <gtest/gtest.h>

#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "ftc/sim/controllers.hpp"
#include "ftc/sim/metrics_record.hpp"
#include "ftc/sim/simulation.hpp"
#include "ftc/sim/spacecraft.hpp"
#include "lanes/closed_loop.hpp"
#include "plants/lane_host.hpp"
#include "plants/spacecraft_dynamics.hpp"
#include "same_bits.hpp"

using namespace ftc::sim;
namespace detail = ftc::sim::detail;

namespace {

// The spacecraft seen only through the Plant interface: the loop calls its f and G through
// ObjectPlantLanes. Its f keeps one angle tracker per angle, as the spacecraft's own does.
class SpacecraftThroughPlant final : public Plant<3, 4> {
 public:
  Vec3 f(const State& x) const override { return sc_.f(x, ws_); }
  Mat34 G(const State& x) const override { return sc_.G(x); }
  std::string model() const override { return "opaque spacecraft"; }

 private:
  Spacecraft sc_;
  mutable Spacecraft::Workspace ws_;
};

// A double integrator on three axes, the fourth actuator idle: f = 0, G = [I 0].
class DoubleIntegrator final : public Plant<3, 4> {
 public:
  Vec3 f(const State&) const override { return Vec3::Zero(); }
  Mat34 G(const State&) const override {
    Mat34 g = Mat34::Zero();
    g.leftCols<3>().setIdentity();
    return g;
  }
  std::string model() const override { return "double integrator"; }
};

// A constant command that records every measurement it is given.
class Recorder final : public Controller<3, 4> {
 public:
  explicit Recorder(const Vec4& u) : u_(u) {}
  void reset() override { seen.clear(); }
  Vec4 step(const Measurement<3>& m) override {
    seen.push_back(m);
    return u_;
  }
  using Controller<3, 4>::step;
  const ControllerConfig& config() const override { return config_; }
  double sample_time() const override { return 0.01; }
  std::vector<Measurement<3>> seen;

 private:
  Vec4 u_;
  ControllerConfig config_;
};

// A run driven by hand: the host's setup and inputs for one lane, the loop stepped once per
// sample with that sample's inputs only, then the results as the host writes them.
SimulationResult step_by_step(const Plant<3, 4>& plant, Controller<3, 4>& controller,
                              const Scenario& s, const SimulationOptions& o) {
  SimulationResult r;
  detail::LaneTask lane;
  lane.config = controller.config();
  lane.scenario = &s;
  lane.options = &o;
  lane.result = &r;
  detail::LaneTask* lanes[1] = {&lane};
  detail::PackSetup<3, 4> su =
      detail::lane_host::pack_setup<3, 4>(lanes, nullptr, nullptr, false, 1);
  detail::lane_host::Host<3, 4> host(lanes, 1, false, su);
  detail::PackFinal<3, 4> fin{};
  host.outputs(fin);
  detail::ControllerBinding<3, 4> binding{&controller, &plant};
  detail::ObjectPlantLanes<3, 4> plant_lanes(detail::object_plant(plant));
  detail::ObjectLaw<3, 4> law(binding.functions());
  detail::MetricLanes<double, 3, 4> metrics(su.metrics);
  detail::ClosedLoop<double, detail::ObjectPlantLanes<3, 4>, detail::ObjectLaw<3, 4>, true, 3, 4>
      loop(su, plant_lanes, law, metrics);
  detail::SampleLanes<3, 4> out;
  for (std::int64_t k = 0; k < su.samples && loop.running(); ++k) {
    loop.step(k, host.inputs(k, 1), nullptr, out);
    host.samples(k, 1, &out);
  }
  loop.finish(fin);
  host.finish(fin);
  return r;
}

using ftc::testing::same_bits;

}  // namespace

// Stepped by hand, one sample's inputs at a time, the loop gives sim::simulate's bits: the final
// state, every field of the metrics record, the recorded trajectory.
TEST(ClosedLoop, StepsCalledOneByOneGiveTheRun) {
  const SpacecraftThroughPlant plant;
  Scenario s = Scenario::paper();
  s.duration = 12.0;
  s.faults[0].onset = 2.0;
  s.faults[1].onset = 5.0;
  SimulationOptions o;
  o.extra_windows = {{0.0, 2.0}, {2.0, 12.0}};
  o.record_every = 7;
  o.metrics.settling_threshold = 0.01;
  o.metrics.steady_state_tail = 1.0;
  const ControllerConfig config = ControllerConfig::table1(ControllerType::pi_fosmc);
  auto a = make_controller(config, plant, s.sample_time);
  auto b = make_controller(config, plant, s.sample_time);
  const SimulationResult want = simulate(plant, *a, s, o);
  const SimulationResult got = step_by_step(plant, *b, s, o);
  ASSERT_EQ(got.samples, want.samples);
  ASSERT_FALSE(want.metrics.diverged);
  for (int i = 0; i < 6; ++i) EXPECT_TRUE(same_bits(got.final_state[i], want.final_state[i])) << i;
  ASSERT_EQ(got.metrics.extra.size(), 2u);
  for (const MetricField& f : kMetricFields) {
    SCOPED_TRACE(std::string(f.name));
    switch (f.scope) {
      case MetricScope::window:
        EXPECT_TRUE(same_bits(got.metrics.errors.*f.in_window, want.metrics.errors.*f.in_window));
        for (std::size_t w = 0; w < 2; ++w)
          EXPECT_TRUE(
              same_bits(got.metrics.extra[w].*f.in_window, want.metrics.extra[w].*f.in_window));
        break;
      case MetricScope::run:
        EXPECT_TRUE(same_bits(got.metrics.*f.per_run, want.metrics.*f.per_run));
        break;
      case MetricScope::fault:
        ASSERT_EQ((got.metrics.*f.per_fault).size(), 2u);
        for (std::size_t i = 0; i < 2; ++i)
          EXPECT_TRUE(same_bits((got.metrics.*f.per_fault)[i], (want.metrics.*f.per_fault)[i]));
        break;
    }
  }
  EXPECT_EQ(got.trajectory.values, want.trajectory.values);
  EXPECT_EQ(got.trajectory.rows(), 12000u / 7u + 1u);
}

// One step is one sample of SPEC §4 on a double integrator (f = 0, G = [I 0]) under a constant
// command u and no disturbance: the controller reads X(t_k) and the acceleration a_k = G·u_{k-1}
// (0 at k = 0, before any command was applied), and RK4, exact on this quadratic, moves X to
// X1(t) = X1(0) + X2(0) t + u t²/2, X2(t) = X2(0) + u t.
TEST(ClosedLoop, StepIsOneSampleOfTheSampledDataLoop) {
  const DoubleIntegrator plant;
  Scenario s;
  s.name = "integrator";
  s.duration = 0.5;
  s.sample_time = 0.01;
  s.substeps = 2;
  s.initial_state = {0.1, -0.2, 0.3, 0.5, 0.25, -1.0};
  const Vec4 u(0.5, -2.0, 1.0, 9.0);  // the fourth actuator moves nothing
  Recorder c(u);
  const SimulationResult r = step_by_step(plant, c, s, SimulationOptions{});
  ASSERT_EQ(r.samples, 50);
  ASSERT_EQ(c.seen.size(), 50u);
  for (std::size_t k = 0; k < c.seen.size(); ++k) {
    const Measurement<3>& m = c.seen[k];
    const double t = static_cast<double>(k) * 0.01;
    EXPECT_EQ(m.t, t);
    for (int i = 0; i < 3; ++i) {
      const double x1 = s.initial_state[i] + s.initial_state[3 + i] * t + 0.5 * u[i] * t * t;
      const double x2 = s.initial_state[3 + i] + u[i] * t;
      EXPECT_NEAR(m.X1[i], x1, 1e-14) << "k = " << k << ", axis " << i;
      EXPECT_NEAR(m.X2[i], x2, 1e-14) << "k = " << k << ", axis " << i;
      EXPECT_EQ(m.a[i], k == 0 ? 0.0 : u[i]) << "k = " << k << ", axis " << i;
    }
  }
  for (int i = 0; i < 3; ++i)
    EXPECT_NEAR(r.final_state[i],
                s.initial_state[i] + s.initial_state[3 + i] * 0.5 + 0.5 * u[i] * 0.25, 1e-13);
  // The metrics of the same samples: the ISE of X1 over the run, the control TV (one change,
  // from 0 to u, is not counted: the first sample has no predecessor).
  double ise = 0.0;
  for (const Measurement<3>& m : c.seen) ise += 0.01 * m.X1.squaredNorm();
  EXPECT_NEAR(r.metrics.errors.ise, ise, 1e-15 * 50);
  EXPECT_EQ(r.metrics.control_tv, 0.0);
  EXPECT_EQ(r.metrics.max_abs_u, 9.0);
}

// The limits and the faults in the loop (SPEC §17.1, every plant): the command is limited, the
// faults act on what is left, and the result is limited again. On the double integrator the
// acceleration the controller reads is the applied output itself: a 50 % loss on actuator 2,
// commanded at −2 with a limit of 1.5, delivers −0.75 (limiting only after the loss gave −1); a
// bias of 2 on actuator 3, commanded at 1, is held at the limit.
TEST(ClosedLoop, TheLimitActsBeforeAndAfterTheFaults) {
  const DoubleIntegrator plant;
  Scenario s;
  s.name = "limited";
  s.duration = 0.1;
  s.sample_time = 0.01;
  s.initial_state = {0, 0, 0, 0, 0, 0};
  Fault loss;
  loss.type = FaultType::loss_of_effectiveness;
  loss.actuator = 2;
  loss.fraction = 0.5;
  Fault bias;
  bias.type = FaultType::bias;
  bias.actuator = 3;
  bias.offset = 2.0;
  s.faults = {loss, bias};
  s.saturation = 1.5;
  Recorder c(Vec4(0.5, -2.0, 1.0, 9.0));
  SimulationOptions o;
  o.record_every = 1;
  const SimulationResult r = simulate(plant, c, s, o);
  ASSERT_EQ(c.seen.size(), 10u);
  for (std::size_t k = 1; k < c.seen.size(); ++k) {
    EXPECT_EQ(c.seen[k].a[0], 0.5) << k;
    EXPECT_EQ(c.seen[k].a[1], -0.75) << k;
    EXPECT_EQ(c.seen[k].a[2], 1.5) << k;
  }
  // The trajectory's applied outputs, the fourth actuator at its limit; the command as given.
  ASSERT_GT(r.trajectory.rows(), 1u);
  const std::size_t last = r.trajectory.rows() - 1;
  EXPECT_EQ(std::vector<double>(r.trajectory.u(last).begin(), r.trajectory.u(last).end()),
            (std::vector<double>{0.5, -0.75, 1.5, 1.5}));
  EXPECT_EQ(r.trajectory.u_d(last)[3], 9.0);
  // Per actuator: limits of 0.25, 4, 4, 4 hold actuator 1 at 0.25 and leave the loss's −1.
  s.saturation = std::vector<double>{0.25, 4.0, 4.0, 4.0};
  Recorder each(Vec4(0.5, -2.0, 1.0, 9.0));
  simulate(plant, each, s, o);
  EXPECT_EQ(each.seen.back().a[0], 0.25);
  EXPECT_EQ(each.seen.back().a[1], -1.0);
  EXPECT_EQ(each.seen.back().a[2], 3.0);
}
