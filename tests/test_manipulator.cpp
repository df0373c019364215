#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>

#include "cli_runner.hpp"
#include "ftc/sim/controller.hpp"
#include "ftc/sim/manipulator.hpp"
#include "ftc/sim/plants.hpp"
#include "ftc/sim/simulation.hpp"
#include "ftc/tune/job/job.hpp"

using nlohmann::json;
using namespace ftc;
using namespace ftc::sim;
using namespace ftc::testing;

namespace {

using Vec2 = Vec<2>;
using State2 = StateOf<2>;

// Non-default parameters, chosen so that every term of M, C and g differs from the others.
// With them m1 lc1² = 0.5, m2 l1² = 2.16, m2 lc2² = 0.135 and m2 l1 lc2 = 0.54, so
//   M11 = 3.145 + 1.08 cos q2,  M12 = 0.235 + 0.54 cos q2,  M22 = 0.235,
//   h = 0.54 sin q2,  g1 = 25.2 cos q1 + 4.05 cos(q1 + q2),  g2 = 4.05 cos(q1 + q2).
ManipulatorParams odd_arm() {
  ManipulatorParams p;
  p.masses = {2.0, 1.5};
  p.lengths = {1.2, 0.8};
  p.centres_of_mass = {0.5, 0.3};
  p.inertias = {0.25, 0.1};
  p.gravity = 9.0;
  return p;
}

State2 state(double q1, double q2, double w1, double w2) {
  State2 x;
  x << q1, q2, w1, w2;
  return x;
}

json manipulator_job() {
  std::ifstream in(std::string(FTC_SOURCE_DIR) + "/jobs/manipulator.json");
  return json::parse(in);
}

class ZeroController final : public Controller<2, 3> {
 public:
  void reset() override {}
  using Controller<2, 3>::step;
  Vec<3> step(const Measurement<2>&) override { return Vec<3>::Zero(); }
  const ControllerConfig& config() const override { return config_; }
  double sample_time() const override { return 1e-3; }

 private:
  ControllerConfig config_;
};

void expect_near(const Eigen::MatrixXd& got, const Eigen::MatrixXd& want, double tol) {
  ASSERT_EQ(got.rows(), want.rows());
  ASSERT_EQ(got.cols(), want.cols());
  for (int i = 0; i < got.rows(); ++i)
    for (int j = 0; j < got.cols(); ++j)
      EXPECT_NEAR(got(i, j), want(i, j), tol) << "(" << i << ", " << j << ")\n" << got;
}

}  // namespace

// State A: q = (0, π/2), q̇ = (1, 2): cos q2 = 0, sin q2 = 1, cos q1 = 1, cos(q1 + q2) = 0.
//   M = [[3.145, 0.235], [0.235, 0.235]], det M = 0.235 · 2.91 = 0.68385
//   C q̇ = [−0.54 (2·1·2 + 2²), 0.54 · 1²] = [−4.32, 0.54],  g = [25.2, 0]
//   −(C q̇ + g) = [−20.88, −0.54]
//   f = M⁻¹ [−20.88, −0.54] = [0.235 (−20.88 + 0.54), −0.235 · −20.88 + 3.145 · −0.54] / 0.68385
//     = [−20.34 / 2.91, 3.2085 / 0.68385]
//   G = M⁻¹ B: M⁻¹ = [[1, −1], [−1, 3.145 / 0.235]] / 2.91; third column = first + second.
TEST(Manipulator, MatchesHandComputedTermsAtRightAngle) {
  const Manipulator arm(odd_arm());
  const State2 x = state(0.0, M_PI / 2, 1.0, 2.0);
  const Vec2 q = x.head<2>(), qd = x.tail<2>();

  Mat<2, 2> M;
  M << 3.145, 0.235, 0.235, 0.235;
  expect_near(arm.mass_matrix(q), M, 1e-14);
  expect_near(arm.coriolis_torque(q, qd), Vec2(-4.32, 0.54), 1e-14);
  expect_near(arm.gravity_torque(q), Vec2(25.2, 0.0), 1e-14);

  expect_near(arm.f(x), Vec2(-20.34 / 2.91, 3.2085 / 0.68385), 1e-12);
  Mat<2, 3> G;
  G << 1 / 2.91, -1 / 2.91, 0.0,  //
      -1 / 2.91, 3.145 / 0.68385, 1 / 0.235;
  expect_near(arm.G(x), G, 1e-12);

  // The same through the model's own identities: M f = −(C q̇ + g) and M G = B.
  expect_near(arm.mass_matrix(q) * arm.f(x), Vec2(-20.88, -0.54), 1e-12);
  expect_near(arm.mass_matrix(q) * arm.G(x), Manipulator::actuator_matrix(), 1e-14);
}

// State B: q = (π/3, −π/3), q̇ = (0.5, 1.5): cos q2 = cos q1 = 1/2, sin q2 = −√3/2,
// cos(q1 + q2) = 1.
//   M = [[3.145 + 0.54, 0.235 + 0.27], [0.505, 0.235]] = [[3.685, 0.505], [0.505, 0.235]]
//   det M = 3.685 · 0.235 − 0.505² = 0.61095
//   h = −0.27 √3;  2 q̇1 q̇2 + q̇2² = 3.75;  C q̇ = [1.0125 √3, −0.0675 √3]
//   g = [25.2 / 2 + 4.05, 4.05] = [16.65, 4.05]
//   f = M⁻¹ r with r = −(C q̇ + g) = [−16.65 − 1.0125 √3, −4.05 + 0.0675 √3]:
//     f1 = (0.235 r1 − 0.505 r2) / 0.61095,  f2 = (−0.505 r1 + 3.685 r2) / 0.61095
//   whose values below were evaluated from these expressions on a calculator (Python floats).
TEST(Manipulator, MatchesHandComputedTermsAtSixtyDegrees) {
  const Manipulator arm(odd_arm());
  const State2 x = state(M_PI / 3, -M_PI / 3, 0.5, 1.5);
  const Vec2 q = x.head<2>(), qd = x.tail<2>();
  const double r3 = std::sqrt(3.0);

  Mat<2, 2> M;
  M << 3.685, 0.505, 0.505, 0.235;
  expect_near(arm.mass_matrix(q), M, 1e-14);
  expect_near(arm.coriolis_torque(q, qd), Vec2(1.0125 * r3, -0.0675 * r3), 1e-14);
  expect_near(arm.gravity_torque(q), Vec2(16.65, 4.05), 1e-13);

  expect_near(arm.f(x), Vec2(-3.8279091921252535, -8.510606078578078), 1e-12);
  Mat<2, 3> G;
  G << 0.235 / 0.61095, -0.505 / 0.61095, -0.27 / 0.61095,  //
      -0.505 / 0.61095, 3.685 / 0.61095, 3.18 / 0.61095;
  expect_near(arm.G(x), G, 1e-12);

  expect_near(arm.mass_matrix(q) * arm.f(x), Vec2(-16.65 - 1.0125 * r3, -4.05 + 0.0675 * r3),
              1e-12);
  expect_near(arm.mass_matrix(q) * arm.G(x), Manipulator::actuator_matrix(), 1e-14);
  // The header's closed form of det M: (m1 lc1² + I1)(m2 lc2² + I2) + m2 l1² (m2 lc2² s2² + I2).
  EXPECT_NEAR(M.determinant(), 0.75 * 0.235 + 2.16 * (0.135 * 0.75 + 0.1), 1e-14);
}

TEST(Manipulator, PseudoInverseIsRightInverseAndMatchesGenericOne) {
  const Manipulator arm(odd_arm());
  for (const State2& x : {state(0.0, 0.0, 0.0, 0.0), state(0.3, -2.8, 1.0, -4.0),
                          state(-1.9, 3.1, 0.2, 0.1), state(5.0, 1.2, -3.0, 2.0)}) {
    const Mat<2, 3> G = arm.G(x);
    const Mat<3, 2> Gp = arm.G_pinv(x);
    expect_near(G * Gp, Mat<2, 2>::Identity(), 1e-13);
    // The closed form B⁺ M(q) is the Moore–Penrose inverse Gᵀ(GGᵀ)⁻¹ of the Plant interface.
    expect_near(Gp, Plant<2, 3>::right_inverse(G), 1e-12);
  }
  expect_near(Manipulator::actuator_matrix() * Manipulator::actuator_pinv(), Mat<2, 2>::Identity(),
              1e-15);
}

// Any one actuator removed (lost, or stuck at a constant that acts as a bias), B keeps full
// row rank: the two that remain still reach every joint torque.
TEST(Manipulator, AnyTwoActuatorsSpanTheJointTorques) {
  const Mat<2, 3> B = Manipulator::actuator_matrix();
  for (int lost = 0; lost < 3; ++lost) {
    Mat<2, 2> rest;
    for (int j = 0, c = 0; j < 3; ++j)
      if (j != lost) rest.col(c++) = B.col(j);
    EXPECT_NEAR(std::abs(rest.determinant()), 1.0, 0.0) << "actuator " << lost + 1 << " lost";
  }
}

TEST(Manipulator, RejectsNonPhysicalParametersByName) {
  ManipulatorParams p;
  p.masses[1] = 0.0;
  p.inertias[0] = -1.0;
  p.gravity = -9.81;
  try {
    Manipulator arm(p);
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    ASSERT_EQ(e.errors().size(), 3u);
    EXPECT_EQ(e.errors()[0].path, "/masses/1");
    EXPECT_EQ(e.errors()[1].path, "/inertias/0");
    EXPECT_EQ(e.errors()[2].path, "/gravity");
  }
}

// The registry knows the arm by name, with its shape and defaults, and the plant it builds runs
// the same loop as simulate() on a Manipulator (bit for bit: both are compiled for the class).
TEST(Manipulator, RegisteredUnderItsModelName) {
  const PlantKind* kind = find_plant_kind("manipulator");
  ASSERT_NE(kind, nullptr);
  EXPECT_EQ(kind->axes, 2);
  EXPECT_EQ(kind->actuators, 3);
  EXPECT_EQ(kind->defaults(),
            (std::vector<double>{1, 1, 1, 1, 0.5, 0.5, 1.0 / 12, 1.0 / 12, 9.81}));
  EXPECT_EQ(kind->default_initial_state.size(), 4u);
  EXPECT_NE(plant_model_names().find("manipulator"), std::string::npos);

  PlantSpec spec;
  spec.model = "manipulator";
  spec.values = kind->defaults();
  spec.values[kind->offset("masses") + 1] = 1.5;
  const auto any = make_plant(spec);
  EXPECT_EQ(any->axes(), 2);
  ManipulatorParams p;
  p.masses[1] = 1.5;
  const Manipulator arm(p);

  Scenario s;
  s.name = "hold";
  s.duration = 2.0;
  s.initial_state = kind->default_initial_state;
  const ControllerConfig cfg = ControllerConfig::table1(ControllerType::pi_fosmc);
  auto c = make_controller(cfg, arm, s.sample_time);
  const SimulationResult direct = simulate(arm, *c, s);
  const SimulationResult via_registry = any->simulate(cfg, s);
  EXPECT_EQ(direct.final_state, via_registry.final_state);
  EXPECT_EQ(direct.metrics.errors.ise, via_registry.metrics.errors.ise);
  EXPECT_GT(direct.metrics.errors.ise, 0.0);

  spec.values[kind->offset("gravity")] = -1.0;
  EXPECT_THROW(make_plant(spec), InputError);
}

// Unforced and undamped, the arm conserves its energy ½ q̇ᵀ M q̇ + V(q). A sign or factor error
// in C(q, q̇) q̇ (which must satisfy q̇ᵀ (Ṁ − 2C) q̇ = 0) or a g(q) that is not the gradient of V
// makes it drift. Without gravity q1 is cyclic and the momentum M11 q̇1 + M12 q̇2 is conserved
// as well. Simulated through the generic loop (sim::simulate with G evaluated at every stage),
// RK4 at 1 ms for 5 s from a state that swings both links through large angles.
TEST(Manipulator, OpenLoopConservesEnergy) {
  for (const double g0 : {0.0, 9.81}) {
    ManipulatorParams p = odd_arm();
    p.gravity = g0;
    const Manipulator arm(p);
    Scenario s;
    s.name = "free";
    s.duration = 5.0;
    s.initial_state = {0.5, -0.4, 1.0, -2.0};
    ZeroController zero;
    SimulationOptions o;
    o.record_every = 1;
    const SimulationResult r = simulate(arm, zero, s, o);
    ASSERT_FALSE(r.metrics.diverged);
    ASSERT_EQ(r.trajectory.rows(), 5000u);

    const auto at = [&](std::size_t k) {
      return Eigen::Map<const State2>(r.trajectory.x(k).data());
    };
    const auto momentum = [&](const State2& x) {
      return (arm.mass_matrix(x.head<2>()) * x.tail<2>())[0];
    };
    const double E0 = arm.energy(at(0)), p0 = momentum(at(0));
    double worst = 0.0, worst_p = 0.0, travel = 0.0;
    for (std::size_t k = 1; k < r.trajectory.rows(); ++k) {
      const State2 x = at(k);
      worst = std::max(worst, std::abs(arm.energy(x) - E0));
      worst_p = std::max(worst_p, std::abs(momentum(x) - p0));
      travel = std::max(travel, std::abs(x[1] - s.initial_state[1]));
    }
    EXPECT_GT(travel, 1.0) << "g0 = " << g0 << ": the elbow should swing through a wide angle";
    // Observed drifts: 2e-13 J without gravity and 2e-8 J with it (E0 = 1.1 J and 15 J); a flipped
    // sign of h in f makes them 0.85 J and 83 J.
    EXPECT_LT(worst, 1e-6) << "g0 = " << g0 << ", E0 = " << E0;
    if (g0 == 0.0) {
      EXPECT_LT(worst_p, 1e-9) << "p0 = " << p0;
    }
  }
}

// Every controller at its Table 1 configuration, unchanged, holding the arm at q = 0 from
// q(0) = (0.5, −0.4) rad under a sinusoidal disturbance on both joints and a 30 % loss of
// effectiveness of actuator 1 (the shoulder motor) at 3 s. The Table 1 gains were designed for
// the spacecraft, and larger losses on this arm are not all recovered by them (see
// docs/model.md (the manipulator section)), so the fault here is one they are expected to ride
// through.
namespace {

constexpr double kFaultOnset = 3.0;  // s
// On ‖q‖ in rad, before the fault (from 2 s on) and after its transient (from 6 s on). Observed
// peaks: NFTSMC 0.029 before and 0.034 after (it keeps a small offset under the fault), FOSMC,
// PI-FOSMC and the adaptive law below 0.003 before and 0.004 after; their transients in [3, 6) s
// reach 0.24-0.41 rad. Under a 70 % loss of actuator 1 instead, the four peak at 0.79-3.8 rad
// after 8 s: the bound separates holding the arm from losing it.
constexpr double kBound = 0.05;

Scenario one_fault_scenario() {
  Scenario s;
  s.name = "loe";
  s.duration = 10.0;
  s.initial_state = {0.5, -0.4, 0.0, 0.0};
  s.disturbance = {{1, Shape::sin, 0.2, 1.0, 0.0}, {2, Shape::cos, 0.2, 2.0, 0.0}};
  Fault loe;
  loe.actuator = 1;
  loe.type = FaultType::loss_of_effectiveness;
  loe.onset = kFaultOnset;
  loe.fraction = 0.3;
  s.faults = {loe};
  return s;
}

}  // namespace

class EveryControllerOnArm : public ::testing::TestWithParam<ControllerType> {};

TEST_P(EveryControllerOnArm, HoldsTheArmNearZeroThroughOneFault) {
  const Manipulator arm;
  const Scenario s = one_fault_scenario();
  auto c = make_controller(ControllerConfig::table1(GetParam()), arm, s.sample_time);
  SimulationOptions o;
  o.record_every = 1;
  const SimulationResult r = simulate(arm, *c, s, o);
  ASSERT_FALSE(r.metrics.diverged);
  ASSERT_EQ(r.trajectory.rows(), 10000u);
  // Peaks of ‖q‖ over [2, 3) s (settled from q(0)), [3, 6) s (the fault's transient) and
  // [6, 10] s (recovered).
  double before = 0.0, transient = 0.0, after = 0.0;
  for (std::size_t k = 0; k < r.trajectory.rows(); ++k) {
    const double t = r.trajectory.t(k);
    const double e = Eigen::Map<const Vec2>(r.trajectory.x(k).data()).norm();
    if (t >= 6.0)
      after = std::max(after, e);
    else if (t >= kFaultOnset)
      transient = std::max(transient, e);
    else if (t >= 2.0)
      before = std::max(before, e);
  }
  EXPECT_LT(before, kBound);
  EXPECT_LT(after, kBound) << "transient peak " << transient;
}

INSTANTIATE_TEST_SUITE_P(Table1, EveryControllerOnArm, ::testing::ValuesIn(kAllControllerTypes),
                         [](const ::testing::TestParamInfo<ControllerType>& p) {
                           return std::string(to_string(p.param));
                         });

TEST(ManipulatorJob, LoadsWithItsPlantAndShape) {
  const tune::Job job = tune::load_job(std::string(FTC_SOURCE_DIR) + "/jobs/manipulator.json");
  EXPECT_EQ(job.name, "manipulator");
  EXPECT_EQ(job.plant.model, "manipulator");
  EXPECT_EQ(job.plant.values, find_plant_kind("manipulator")->defaults());
  ASSERT_EQ(job.scenarios.size(), 1u);
  EXPECT_EQ(job.scenarios[0].initial_state, (std::vector<double>{0.5, -0.4, 0.0, 0.0}));
  EXPECT_EQ(job.scenarios[0].faults.size(), 2u);
  EXPECT_EQ(job.compare.size(), 2u);
  ASSERT_TRUE(job.tuning.has_value());
  EXPECT_EQ(job.tuning->algorithm->evaluations(), 110);
}

// A scenario without an initial state starts from its plant's default: four values for the arm
// (the spacecraft's six were filled in before, and the job was refused).
TEST(ManipulatorJob, StartsFromTheArmsStateWhenTheJobGivesNone) {
  std::ifstream in(std::string(FTC_SOURCE_DIR) + "/jobs/manipulator.json");
  json j = json::parse(in);
  j["scenarios"][0].erase("initial_state");
  const tune::Job job = tune::parse_job(j, "manipulator.json");
  EXPECT_EQ(job.scenarios[0].initial_state, find_plant_kind("manipulator")->default_initial_state);
}

TEST(ManipulatorJob, RejectsIndicesAndStatesOfTheWrongShape) {
  const auto errors_of = [](const json& j) {
    try {
      tune::parse_job(j, "manipulator.json");
    } catch (const InputError& e) {
      return e.errors();
    }
    return std::vector<FieldError>{};
  };
  const auto expect_error = [](const std::vector<FieldError>& errs, const std::string& path,
                               const std::string& message) {
    std::string all;
    bool found = false;
    for (const FieldError& e : errs) {
      all += "\n  " + to_string(e);
      found = found || (e.path == path && e.message.find(message) != std::string::npos);
    }
    EXPECT_TRUE(found) << "expected " << path << " ~ " << message << ", got" << all;
  };

  json j = manipulator_job();
  j["scenarios"][0]["faults"][1]["actuator"] = 4;  // fine for the spacecraft, not here
  expect_error(errors_of(j), "/scenarios/0/faults/1/actuator", "1..3");

  j = manipulator_job();
  j["scenarios"][0]["initial_state"] = {-0.7, -0.07, 1.5, 0.3, 1.3, -0.2};  // a spacecraft's
  expect_error(errors_of(j), "/scenarios/0/initial_state",
               "expected 4 numbers (X1 and X2 of the plant's 2 axes), got 6");

  j = manipulator_job();
  j["scenarios"][0]["disturbance"][0]["axis"] = 3;
  expect_error(errors_of(j), "/scenarios/0/disturbance/0/axis", "1..2");

  j = manipulator_job();
  j["plant"]["masses"] = {1, 0};
  expect_error(errors_of(j), "/plant/masses/1", "must be > 0");
}

// The job end to end through the binary, cut down to 4 bats × 2 iterations.
TEST(ManipulatorJob, CliRunWritesGainsForTheManipulator) {
  const auto dir = fresh_dir("manipulator");
  json j = manipulator_job();
  j["tuning"]["algorithm"]["population"] = 4;
  j["tuning"]["algorithm"]["iterations"] = 2;
  {
    std::ofstream f(dir / "job.json");
    f << j.dump(2);
  }
  const CliResult r = run_cli(
      "run '" + (dir / "job.json").string() + "' -q --out '" + (dir / "out").string() + "'", dir);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const json g = json::parse(slurp(dir / "out" / "gains.json"));
  EXPECT_EQ(g["plant"]["model"], "manipulator");
  EXPECT_EQ(g["controller"]["type"], "pi_fosmc");
  EXPECT_GT(g["objective"]["value"].get<double>(), 0.0);
  const std::string md = slurp(dir / "out" / "comparison.md");
  for (const char* label : {"| NFTSMC", "| FOSMC", "| PI-FOSMC (job)", "| tuned PI-FOSMC"})
    EXPECT_NE(md.find(label), std::string::npos) << label;
}
