// The rigid_body and multirotor plants (SPEC §17): f, G and G⁺ against the facts §17.1 lists and
// hand-computed values, G G⁺ = I for any tensor and geometry, energy and angular momentum
// conserved without control, the presets' axes and rotors, the minimum-norm hover trim, the
// checks of tensors, axes and layouts at their JSON paths, the model_invalid flag past 85° of
// pitch, every lane giving the scalar bits, and hexa_x giving the hexarotor's bits.
#include <gtest/gtest.h>

#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "ftc/runtime/plant_json.hpp"
#include "ftc/runtime/scenario_json.hpp"
#include "ftc/runtime/schema.hpp"
#include "ftc/sim/controller_config.hpp"
#include "ftc/sim/controllers.hpp"
#include "ftc/sim/input_error.hpp"
#include "ftc/sim/isa.hpp"
#include "ftc/sim/plants.hpp"
#include "ftc/sim/rigid_body.hpp"
#include "ftc/sim/simulation.hpp"
#include "ftc/sim/vehicles.hpp"
#include "same_bits.hpp"

using namespace ftc;
using namespace ftc::sim;
using nlohmann::json;

namespace {

using ftc::testing::same_bits;

// The plant a spec describes, as a job's plant block would build it.
std::unique_ptr<AnyPlant> plant_of(const RigidBodySpec& s) {
  return make_plant({"rigid_body", to_values(s)});
}
std::unique_ptr<AnyPlant> plant_of(const MultirotorSpec& s) {
  return make_plant({"multirotor", to_values(s)});
}

// A full tensor with products of inertia, positive definite.
constexpr std::array<double, 9> kTensor{0.25, 0.01, -0.005, 0.01, 0.30, 0.008, -0.005, 0.008, 0.18};

RigidBody body(const std::array<double, 9>& J, const std::string& preset,
               std::vector<std::array<double, 3>> axes = {}) {
  RigidBodySpec s;
  s.inertia = J;
  s.preset = preset;
  s.axes = std::move(axes);
  return RigidBody(rigid_body_params(s));
}

RigidBody::State state(double a, double b, double c, double d, double e, double f) {
  RigidBody::State x;
  x << a, b, c, d, e, f;
  return x;
}

std::vector<FieldError> plant_errors(const json& plant) {
  sim::PlantSpec spec;
  schema::Errors errs;
  schema::read(*runtime::plant_shape(), plant, "/plant", spec, errs);
  return errs;
}

bool has(const std::vector<FieldError>& errs, const std::string& path, const std::string& text) {
  for (const FieldError& e : errs)
    if (e.path == path && e.message.find(text) != std::string::npos) return true;
  return false;
}

std::string listed(const std::vector<FieldError>& errs) {
  std::string s;
  for (const FieldError& e : errs) s += e.path + ": " + e.message + "\n";
  return s;
}

Scenario scenario(double duration = 4.0) {
  Scenario s;
  s.name = "s";
  s.duration = duration;
  s.sample_time = 0.01;
  s.initial_state = {0.2, -0.15, 0.1, 0.0, 0.0, 0.0};
  return s;
}

// RK4 on f alone (no control, no disturbance).
RigidBody::State coast(const RigidBody& p, RigidBody::State x, double h, int steps) {
  const auto d = [&](const RigidBody::State& s) {
    RigidBody::State out;
    out.head<3>() = s.tail<3>();
    out.tail<3>() = p.f(s);
    return out;
  };
  for (int i = 0; i < steps; ++i) {
    const RigidBody::State k1 = d(x), k2 = d(x + 0.5 * h * k1), k3 = d(x + 0.5 * h * k2),
                           k4 = d(x + h * k3);
    x += h / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4);
  }
  return x;
}

// Body rates ω = W(X1) Ẋ1.
Vec3 body_rates(const RigidBody::State& x) {
  const double sf = std::sin(x[0]), cf = std::cos(x[0]), st = std::sin(x[1]), ct = std::cos(x[1]);
  Mat<3, 3> W;
  W << 1, 0, -st, 0, cf, sf * ct, 0, -sf, cf * ct;
  return W * x.tail<3>();
}

// The body-to-inertial rotation of 3-2-1 Euler angles (yaw, then pitch, then roll).
Mat<3, 3> rotation(const RigidBody::State& x) {
  const double f = x[0], t = x[1], p = x[2];
  Mat<3, 3> Rz, Ry, Rx;
  Rz << std::cos(p), -std::sin(p), 0, std::sin(p), std::cos(p), 0, 0, 0, 1;
  Ry << std::cos(t), 0, std::sin(t), 0, 1, 0, -std::sin(t), 0, std::cos(t);
  Rx << 1, 0, 0, 0, std::cos(f), -std::sin(f), 0, std::sin(f), std::cos(f);
  return Rz * Ry * Rx;
}

}  // namespace

// SPEC §17.1's facts: at X1 = 0, W = I and Ẇ Ẋ1 = (−x5 x6, x4 x6, −x4 x5); with J diagonal and
// D = I₃ there, G = J⁻¹ and f = ((kx + 1) x5 x6, (ky − 1) x4 x6, (kz + 1) x4 x5).
TEST(RigidBody, MatchesSpecFactsAtZeroAttitude) {
  const double Ix = 2.0, Iy = 3.0, Iz = 5.0;
  const RigidBody p = body({Ix, 0, 0, 0, Iy, 0, 0, 0, Iz}, "orthogonal");
  const RigidBody::State x = state(0, 0, 0, 0.3, -0.4, 0.7);
  const double kx = (Iy - Iz) / Ix, ky = (Iz - Ix) / Iy, kz = (Ix - Iy) / Iz;
  const Vec3 f = p.f(x);
  EXPECT_NEAR(f[0], (kx + 1) * -0.4 * 0.7, 1e-15);
  EXPECT_NEAR(f[1], (ky - 1) * 0.3 * 0.7, 1e-15);
  EXPECT_NEAR(f[2], (kz + 1) * 0.3 * -0.4, 1e-15);
  const auto G = p.G(x);
  EXPECT_NEAR(G(0, 0), 1 / Ix, 1e-15);
  EXPECT_NEAR(G(1, 1), 1 / Iy, 1e-15);
  EXPECT_NEAR(G(2, 2), 1 / Iz, 1e-15);
  EXPECT_EQ(G(0, 1), 0.0);
  EXPECT_EQ(p.actuator_count(), 3);
  for (int j = 3; j < kMaxBodyActuators; ++j) EXPECT_EQ(G.col(j).norm(), 0.0) << j;
}

// f(X1, 0) = 0 for every attitude with |θ| < 90°, with a full tensor.
TEST(RigidBody, AtRestNoDriftAtAnyAttitude) {
  const RigidBody p = body(kTensor, "pyramid");
  for (double phi : {-2.0, 0.3, 1.1})
    for (double theta : {-1.4, -0.2, 0.9, 1.45})
      for (double psi : {-3.0, 0.5}) {
        const Vec3 f = p.f(state(phi, theta, psi, 0, 0, 0));
        EXPECT_EQ(f.norm(), 0.0) << phi << " " << theta << " " << psi;
      }
}

// G G⁺ = I for tensors and geometries: the presets, 5 skewed axes, a multirotor's rotors.
TEST(RigidBody, PseudoInverseIsARightInverse) {
  const std::vector<RigidBody> plants = {
      body(kTensor, "pyramid"), body(kTensor, "nasa"),
      body({1, 0, 0, 0, 2, 0, 0, 0, 3}, "orthogonal"),
      body(kTensor, "", {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {1, 1, 0}, {0.2, -0.5, 1}}),
      RigidBody(multirotor_params(MultirotorSpec{}))};
  for (const RigidBody& p : plants)
    for (const RigidBody::State& x :
         {state(0, 0, 0, 0, 0, 0), state(0.4, -0.9, 2.0, 0.3, 0.1, -0.2),
          state(-1.2, 1.3, -0.5, 1, 2, 3)}) {
      const Mat<3, 3> I = p.G(x) * p.G_pinv(x);
      EXPECT_LT((I - Mat<3, 3>::Identity()).norm(), 1e-12) << p.model() << "\n" << I;
    }
}

// Without control a torque-free rigid body keeps its rotational energy ½ ωᵀ J ω and its angular
// momentum in the inertial frame, R(X1) J ω: the Euler kinematics (W, Ẇ) agree with Euler's
// equation. 20 s of RK4 at 1 ms from a tumbling start, with a full tensor.
TEST(RigidBody, ConservesEnergyAndAngularMomentumWithoutControl) {
  const RigidBody p = body(kTensor, "pyramid");
  const Mat<3, 3> J =
      Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(kTensor.data());
  const RigidBody::State x0 = state(0.3, -0.4, 0.2, 0.2, -0.3, 0.25);
  const auto energy = [&](const RigidBody::State& x) {
    const Vec3 w = body_rates(x);
    return 0.5 * w.dot(J * w);
  };
  const auto momentum = [&](const RigidBody::State& x) -> Vec3 {
    return rotation(x) * (J * body_rates(x));
  };
  const RigidBody::State x1 = coast(p, x0, 1e-3, 20000);
  ASSERT_LT(std::abs(x1[1]), 1.4) << "stayed away from the singularity";
  EXPECT_NEAR(energy(x1) / energy(x0), 1.0, 1e-9);
  EXPECT_LT((momentum(x1) - momentum(x0)).norm() / momentum(x0).norm(), 1e-9)
      << momentum(x0).transpose() << " -> " << momentum(x1).transpose();
  // The attitude did move: the test is not of a body at rest.
  EXPECT_GT((x1 - x0).head<3>().norm(), 1.0);
}

// The presets' axes: pyramid wheels equally inclined to the body axes (each component ±1/√3 at
// the default β), nasa's fourth along (1, 1, 1)/√3; β sets the elevation.
TEST(RigidBody, PresetAxesAreTheSpecs) {
  const double k = 1.0 / std::sqrt(3.0);
  const RigidBody pyr = body({1, 0, 0, 0, 1, 0, 0, 0, 1}, "pyramid");
  const auto D = pyr.torque_matrix();
  const double signs[4][2] = {{1, 1}, {-1, 1}, {-1, -1}, {1, -1}};
  for (int j = 0; j < 4; ++j) {
    EXPECT_NEAR(D(0, j), signs[j][0] * k, 1e-15) << j;
    EXPECT_NEAR(D(1, j), signs[j][1] * k, 1e-15) << j;
    EXPECT_NEAR(D(2, j), k, 1e-15) << j;
  }
  const RigidBody nasa = body({1, 0, 0, 0, 1, 0, 0, 0, 1}, "nasa");
  EXPECT_NEAR(nasa.torque_matrix()(0, 3), k, 1e-15);
  EXPECT_NEAR(nasa.torque_matrix()(2, 3), k, 1e-15);
  EXPECT_EQ(nasa.torque_matrix()(0, 0), 1.0);
  RigidBodySpec s;
  s.beta_deg = 30.0;
  const RigidBody p30(rigid_body_params(s));
  EXPECT_NEAR(p30.torque_matrix()(2, 0), 0.5, 1e-15);
  EXPECT_NEAR(p30.torque_matrix()(0, 0), std::cos(M_PI / 6) / std::sqrt(2.0), 1e-15);
  // A user's axes are normalised.
  const RigidBody own = body(kTensor, "", {{2, 0, 0}, {0, 3, 0}, {0, 0, 0.5}});
  EXPECT_EQ(own.torque_matrix()(0, 0), 1.0);
  EXPECT_EQ(own.torque_matrix()(1, 1), 1.0);
  EXPECT_EQ(own.torque_matrix()(2, 2), 1.0);
}

// A preset's rotors share the weight equally; a lopsided list gets the minimum-norm thrusts
// with zero torque that carry m g (checked against the normal equations by hand), within its
// limits; a layout that cannot hover is refused at the rotor that fails.
TEST(Multirotor, HoverTrimIsTheMinimumNormSolution) {
  MultirotorSpec quad;
  for (double t : hover_thrusts(quad)) EXPECT_EQ(t, 1.5 * 9.81 / 4.0);
  MultirotorSpec own;
  own.preset.clear();
  own.rotors = {{{0.3, 0.0}, 1, 10, 0.02},
                {{0.0, 0.2}, -1, 10, 0.02},
                {{-0.3, 0.0}, 1, 10, 0.02},
                {{0.0, -0.25}, -1, 10, 0.02}};
  const std::vector<double> T = hover_thrusts(own);
  ASSERT_EQ(T.size(), 4u);
  // Zero torque: roll 0.2 T2 − 0.25 T4 = 0, pitch −0.3 T1 + 0.3 T3 = 0, yaw κ(T1 − T2 + T3 − T4)
  // = 0; with Σ T = m g = 14.715: T1 = T3 = 14.715/4 and T2 + T4 = 14.715/2, 0.2 T2 = 0.25 T4,
  // so T2 = 14.715/2 · 5/9 and T4 = 14.715/2 · 4/9 (four equations, four unknowns: unique).
  EXPECT_NEAR(T[0], 14.715 / 4, 1e-12);
  EXPECT_NEAR(T[2], 14.715 / 4, 1e-12);
  EXPECT_NEAR(T[1], 14.715 / 2 * 5 / 9, 1e-12);
  EXPECT_NEAR(T[3], 14.715 / 2 * 4 / 9, 1e-12);
  const RigidBody p(multirotor_params(own));
  for (int i = 0; i < 4; ++i) {
    EXPECT_NEAR(p.actuator_trim().u0[static_cast<std::size_t>(i)], T[static_cast<std::size_t>(i)],
                0);
    EXPECT_EQ(p.actuator_trim().hi[static_cast<std::size_t>(i)],
              10 - T[static_cast<std::size_t>(i)]);
  }
  own.rotors[1].max_thrust = 4.0;  // rotor 2 must give 4.0875 N
  EXPECT_TRUE(has(validate(own, ""), "/rotors/1", "cannot hover")) << listed(validate(own, ""));
  MultirotorSpec heavy;
  heavy.mass = 4.0;  // 39.24 N on four rotors of 8 N
  EXPECT_TRUE(has(validate(heavy, ""), "/rotors/max_thrust", "cannot hover"));
  // Every rotor clockwise: the drag torques add up and no thrusts carry the weight without yaw.
  MultirotorSpec same_spin = own;
  for (RotorSpec& r : same_spin.rotors) r.spin = 1;
  EXPECT_TRUE(has(validate(same_spin, ""), "/rotors", "no thrusts give zero torque"))
      << listed(validate(same_spin, ""));
  // Every rotor on the x axis: no roll torque at all.
  MultirotorSpec in_line = own;
  for (RotorSpec& r : in_line.rotors) r.position[1] = 0.0;
  EXPECT_TRUE(has(validate(in_line, ""), "/rotors", "cannot make a torque about every axis"))
      << listed(validate(in_line, ""));
}

// hexa_x with the hexarotor's numbers is the hexarotor, to the last bit: every controller, a
// rotor loss, model mismatch and a saturation.
TEST(Multirotor, HexaXGivesTheHexarotorsBits) {
  PlantSpec hexa;
  hexa.model = "hexarotor";
  MultirotorSpec m;
  m.inertia = {0.011, 0, 0, 0, 0.015, 0, 0, 0, 0.021};
  m.mass = 2.02;
  m.gravity = 9.81;
  m.preset = "hexa_x";
  m.arm_length = 0.243;
  m.max_thrust = 19.2343;
  m.moment_constant = 0.06;
  PlantSpec multi;
  multi.model = "multirotor";
  multi.values = to_values(m);
  const auto a = make_plant(hexa), b = make_plant(multi);
  EXPECT_EQ(b->actuators(), 6);
  Scenario s = scenario(3.0);
  s.sample_time = 0.001;
  s.disturbance = {{1, Shape::sin, 0.2, 1.0, 0.0}};
  Fault loss;
  loss.actuator = 2;
  loss.type = FaultType::loss_of_effectiveness;
  loss.fraction = 0.4;
  loss.onset = 1.0;
  s.faults = {loss};
  s.saturation = 6.0;
  Scenario t = s;
  t.set_true_value("inertia", {0.012, 0.015, 0.02});
  SimulationOptions o;
  o.record_every = 7;
  for (ControllerType type : kAllControllerTypes)
    for (const Scenario* sc : {&s, &t}) {
      const ControllerConfig c = ControllerConfig::table1(type);
      const SimulationResult ra = a->simulate(c, *sc, o), rb = b->simulate(c, *sc, o);
      ASSERT_EQ(ra.trajectory.values.size(), rb.trajectory.values.size());
      for (std::size_t i = 0; i < ra.trajectory.values.size(); ++i)
        ASSERT_TRUE(same_bits(ra.trajectory.values[i], rb.trajectory.values[i]))
            << to_string(type) << " value " << i;
      EXPECT_TRUE(same_bits(ra.metrics.errors.ise, rb.metrics.errors.ise));
      EXPECT_TRUE(same_bits(ra.metrics.control_tv, rb.metrics.control_tv));
      EXPECT_FALSE(rb.model_invalid.has_value());
    }
}

// Every lane of a pack on every instruction set gives the bits of the simulation alone, for a
// full tensor with Euler kinematics and per-wheel limits, lanes with their own true tensor (full
// or diagonal).
TEST(RigidBody, EveryLaneGivesTheScalarBits) {
  RigidBodySpec spec;
  spec.inertia = kTensor;
  spec.max = {0.05, 0.04, 0.05, 0.06};
  const auto plant = plant_of(spec);
  for (ControllerType type : kAllControllerTypes)
    for (Isa isa : supported_isas()) {
      const int n = lane_width(isa) + 1;
      std::vector<ControllerConfig> configs(n);
      std::vector<Scenario> scenarios(n, scenario());
      std::vector<SimulationOptions> options(n);
      std::vector<PackTask> tasks;
      for (int l = 0; l < n; ++l) {
        configs[l] = ControllerConfig::table1(type);
        configs[l].switching_gain = 0.02 * (1.0 + 0.1 * l);
        Fault f;
        f.actuator = 1 + l % 4;
        f.type = FaultType::stuck;
        f.value = 0.01 * l;
        f.onset = 1.0 + 0.2 * l;
        scenarios[l].faults = {f};
        if (l % 2 == 1) {
          std::vector<double> J(kTensor.begin(), kTensor.end());
          J[0] *= 1.0 + 0.05 * l;
          scenarios[l].set_true_value("inertia", J);
        }
        if (l % 3 == 2) scenarios[l].saturation = std::vector<double>{0.03, 0.02, 0.03, 0.04};
        // A diagonal true tensor among full ones: each lane takes the form of its own J, so it
        // gives its bits whatever the pack holds beside it.
        if (l % 4 == 3) scenarios[l].set_true_value("inertia", {0.25, 0.30, 0.18});
        // Actuators of the simulated plant turned and weakened, lane by lane.
        if (l % 3 == 1) {
          scenarios[l].set_true_value("actuator_scale", {1.0, 0.9 - 0.01 * l, 1.0, 1.1});
          scenarios[l].set_true_value("actuator_misalignment", {0.0, 0.0, 0.02 * l, -0.01});
        }
        options[l].record_every = l == 0 ? 0 : 9;
        tasks.push_back({&configs[l], &scenarios[l], &options[l]});
      }
      std::vector<SimulationResult> got(n);
      std::vector<std::string> errors(n);
      plant->simulate_pack(tasks, got, errors, isa);
      for (int l = 0; l < n; ++l) {
        const std::string what =
            std::string(to_string(type)) + " on " + to_string(isa) + ", lane " + std::to_string(l);
        ASSERT_EQ(errors[l], "") << what;
        const SimulationResult want = plant->simulate(configs[l], scenarios[l], options[l]);
        for (std::size_t i = 0; i < want.final_state.size(); ++i)
          EXPECT_TRUE(same_bits(got[l].final_state[i], want.final_state[i])) << what;
        EXPECT_TRUE(same_bits(got[l].metrics.errors.ise, want.metrics.errors.ise)) << what;
        ASSERT_EQ(got[l].trajectory.values.size(), want.trajectory.values.size()) << what;
        for (std::size_t i = 0; i < want.trajectory.values.size(); ++i)
          ASSERT_TRUE(same_bits(got[l].trajectory.values[i], want.trajectory.values[i])) << what;
        EXPECT_EQ(got[l].model_invalid, std::optional<bool>(false)) << what;

        if (options[l].record_every > 0) {
          EXPECT_EQ(got[l].trajectory.actuators, 4) << what;
        }
      }
    }
}

// A run whose pitch passes 85° is flagged (the metrics still count); one that stays below is
// not. The wheels' limit holds: no applied output beyond it.
TEST(RigidBody, FlagsARunPastEightyFiveDegreesOfPitch) {
  RigidBodySpec spec;
  spec.max = {0.01};
  const auto plant = plant_of(spec);
  ControllerConfig c = ControllerConfig::table1(ControllerType::pi_fosmc);
  c.switching_gain = 0.01;
  // Pitching up at 0.6 rad/s from 1.2 rad, which the wheels (at most 0.04 rad/s² about pitch)
  // cannot stop before 85° = 1.4835 rad (reached near 0.5 s); 90° is not reached by 0.6 s.
  Scenario steep = scenario(0.6);
  steep.initial_state = {0.0, 1.2, 0.0, 0.0, 0.6, 0.0};
  SimulationOptions o;
  o.record_every = 1;
  const SimulationResult r = plant->simulate(c, steep, o);
  ASSERT_TRUE(r.model_invalid.has_value());
  EXPECT_TRUE(*r.model_invalid);
  double peak = 0;
  for (std::size_t i = 0; i < r.trajectory.rows(); ++i) {
    peak = std::max(peak, std::abs(r.trajectory.x(i)[1]));
    for (double u : r.trajectory.u(i)) EXPECT_LE(std::abs(u), 0.01);
  }
  EXPECT_GT(peak, 85.0 * M_PI / 180.0);
  EXPECT_LT(peak, 0.5 * M_PI);
  const SimulationResult calm = plant->simulate(c, scenario(0.6), o);
  EXPECT_EQ(calm.model_invalid, std::optional<bool>(false));
}

// The job file's forms: a 3-list or a 3×3 tensor, axes or a preset, max as one number or one per
// actuator; each bad form at its JSON path with what was wrong, and a written plant reads back
// to the same values.
TEST(RigidBodyJob, ReadsWritesAndRefusesAtThePath) {
  const json good = {
      {"model", "rigid_body"},
      {"inertia", {{0.25, 0.01, -0.005}, {0.01, 0.30, 0.008}, {-0.005, 0.008, 0.18}}},
      {"actuators",
       {{"axes", {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {1, 1, 1}, {1, -1, 0}}},
        {"max", {0.1, 0.1, 0.1, 0.2, 0.2}}}}};
  EXPECT_TRUE(plant_errors(good).empty()) << listed(plant_errors(good));
  PlantSpec spec;
  schema::Errors errs;
  schema::read(*runtime::plant_shape(), good, "", spec, errs);
  ASSERT_TRUE(errs.empty());
  EXPECT_EQ(find_plant_kind("rigid_body")->actuators_of(spec.values), 5);
  const json written = runtime::plant_shape()->write(spec);
  EXPECT_EQ(written["inertia"], good["inertia"]);
  PlantSpec again;
  schema::read(*runtime::plant_shape(), written, "", again, errs);
  EXPECT_EQ(again.values, spec.values);
  EXPECT_EQ(make_plant(spec)->actuators(), 5);

  json j = good;
  j["inertia"][0][1] = 0.02;
  EXPECT_TRUE(has(plant_errors(j), "/plant/inertia/1/0", "must be symmetric"))
      << listed(plant_errors(j));
  j = good;
  j["inertia"] = {{1, 2, 0}, {2, 1, 0}, {0, 0, 1}};
  EXPECT_TRUE(has(plant_errors(j), "/plant/inertia", "leading 2×2 minor is -3"))
      << listed(plant_errors(j));
  j = good;
  j["inertia"] = {1, -2, 3};
  EXPECT_TRUE(has(plant_errors(j), "/plant/inertia/1", "must be > 0")) << listed(plant_errors(j));
  j = good;
  j["actuators"] = {{"axes", {{1, 0, 0}, {0, 1, 0}, {1, 1, 0}}}};
  EXPECT_TRUE(has(plant_errors(j), "/plant/actuators/axes", "must span R³"))
      << listed(plant_errors(j));
  j["actuators"] = {{"axes", json::array({{1, 0, 0}, {0, 1, 0}})}};
  EXPECT_TRUE(
      has(plant_errors(j), "/plant/actuators/axes", "expected 3 to 8 actuator axes, got 2"));
  j["actuators"] = {{"axes", {{1, 0, 0}, {0, 0, 0}, {0, 1, 0}, {0, 0, 1}}}};
  EXPECT_TRUE(has(plant_errors(j), "/plant/actuators/axes/1", "non-zero"))
      << listed(plant_errors(j));
  j["actuators"] = {{"preset", "pyramidd"}};
  EXPECT_TRUE(
      has(plant_errors(j), "/plant/actuators/preset", "supported: orthogonal, pyramid, nasa"));
  j["actuators"] = {{"preset", "pyramid"}, {"max", {1, 2}}};
  EXPECT_TRUE(has(plant_errors(j), "/plant/actuators/max", "one per actuator (4), got 2"));
  j["actuators"] = {{"preset", "pyramid"}, {"max", {1, 2, -1, 3}}};
  EXPECT_TRUE(has(plant_errors(j), "/plant/actuators/max/2", "> 0 (got -1)"));
  j["actuators"] = {{"preset", "nasa"}, {"beta_deg", 30}};
  EXPECT_TRUE(has(plant_errors(j), "/plant/actuators/beta_deg", "pyramid preset only"));
  j["actuators"] = {{"preset", "pyramid"}, {"beta_deg", 0}};
  EXPECT_TRUE(has(plant_errors(j), "/plant/actuators/beta_deg", "strictly between 0 and 90"));
  // The principal-moment plants say what they take.
  EXPECT_TRUE(
      has(plant_errors({{"model", "spacecraft"}, {"inertia", {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}}}}),
          "/plant/inertia", "use the rigid_body or multirotor plant"));
}

TEST(MultirotorJob, ReadsAListOrAPresetAndRefusesAtThePath) {
  const json quad = {{"model", "multirotor"}, {"rotors", {{"preset", "quad_x"}}}};
  EXPECT_TRUE(plant_errors(quad).empty()) << listed(plant_errors(quad));
  json list = {
      {"model", "multirotor"},
      {"mass", 1.2},
      {"rotors",
       {{{"position", {0.2, 0.2}}, {"spin", "cw"}, {"max_thrust", 7}, {"moment_constant", 0.015}},
        {{"position", {-0.2, 0.2}}, {"spin", "ccw"}, {"max_thrust", 7}, {"moment_constant", 0.015}},
        {{"position", {-0.2, -0.2}}, {"spin", "cw"}, {"max_thrust", 7}, {"moment_constant", 0.015}},
        {{"position", {0.2, -0.2}}, {"spin", "ccw"}, {"max_thrust", 7}, {"moment_constant", 0.015}},
        {{"position", {0.0, 0.3}},
         {"spin", "cw"},
         {"max_thrust", 7},
         {"moment_constant", 0.015}}}}};
  EXPECT_TRUE(plant_errors(list).empty()) << listed(plant_errors(list));
  PlantSpec spec;
  schema::Errors errs;
  schema::read(*runtime::plant_shape(), list, "", spec, errs);
  EXPECT_EQ(make_plant(spec)->actuators(), 5);
  list["rotors"][4]["spin"] = "left";
  EXPECT_TRUE(has(plant_errors(list), "/plant/rotors/4/spin", "\"cw\" or \"ccw\""));
  list["rotors"][4].erase("spin");
  EXPECT_TRUE(has(plant_errors(list), "/plant/rotors/4/spin", "is required"));
  EXPECT_TRUE(has(plant_errors({{"model", "multirotor"}, {"rotors", {{"preset", "tri"}}}}),
                  "/plant/rotors/preset", "quad_x, quad_plus, hexa_x, octa_x"));
  EXPECT_TRUE(has(plant_errors({{"model", "multirotor"}, {"mass", 9}}), "/plant/rotors/max_thrust",
                  "cannot hover"));
}

// A scenario's true tensor (a 3×3, or 3 principal moments) is the simulated plant's; the ensemble
// scale S J S keeps a tensor symmetric.
TEST(RigidBody, TrueTensorAndItsEnsembleScaling) {
  const Scenario s = runtime::scenario_from_json(
      {{"name", "t"}, {"duration", 1}, {"inertia", {{0.3, 0.01, 0}, {0.01, 0.3, 0}, {0, 0, 0.2}}}},
      "test");
  ASSERT_NE(s.true_value("inertia"), nullptr);
  EXPECT_EQ(s.true_value("inertia")->size(), 9u);
  const PlantKind& k = *find_plant_kind("rigid_body");
  const std::vector<double> v =
      k.with_true_values(k.defaults(), {{"inertia", {0.3, 0.4, 0.5}}}, "");
  const std::vector<double> J = k.parameter_values(v, "inertia");
  EXPECT_EQ(J, (std::vector<double>{0.3, 0, 0, 0, 0.4, 0, 0, 0, 0.5}));
  std::vector<double> t(kTensor.begin(), kTensor.end());
  PlantKind::scale(*k.find_uncertain("inertia"), t, std::vector<double>{4.0, 1.0, 0.25});
  EXPECT_DOUBLE_EQ(t[0], 1.0);
  EXPECT_DOUBLE_EQ(t[1], 0.02);  // √(4·1) · 0.01
  EXPECT_DOUBLE_EQ(t[3], 0.02);
  EXPECT_DOUBLE_EQ(t[2], -0.005);  // √(4·0.25) · −0.005
  EXPECT_DOUBLE_EQ(t[8], 0.045);
}

// SPEC §17.1 by hand: a misaligned axis turns right-handedly about â × ẑ (x̂ about −ŷ, toward
// +z), or about â × x̂ for an axis along ẑ (ẑ about ŷ, toward +x); a scaled one keeps its axis.
TEST(RigidBody, MisalignedAndScaledActuatorsOfTheSimulatedPlantCheckedByHand) {
  const double t = 0.3, c = std::cos(t), sn = std::sin(t);
  const auto x = misaligned_axis({1.0, 0.0, 0.0}, t);
  EXPECT_NEAR(x[0], c, 1e-15);
  EXPECT_EQ(x[1], 0.0);
  EXPECT_NEAR(x[2], sn, 1e-15);
  const auto z = misaligned_axis({0.0, 0.0, 1.0}, t);
  EXPECT_NEAR(z[0], sn, 1e-15);
  EXPECT_EQ(z[1], 0.0);
  EXPECT_NEAR(z[2], c, 1e-15);
  const std::array<double, 3> p{0.5, 0.5, std::sqrt(0.5)};
  EXPECT_EQ(misaligned_axis(p, 0.0), p);
  const auto q = misaligned_axis(p, t);  // still a unit vector, at angle t from p
  EXPECT_NEAR(q[0] * q[0] + q[1] * q[1] + q[2] * q[2], 1.0, 1e-15);
  EXPECT_NEAR(q[0] * p[0] + q[1] * p[1] + q[2] * p[2], c, 1e-15);

  // The orthogonal triad with wheel 1 turned by t and wheel 2 at half effectiveness: at X1 = 0,
  // G = J⁻¹ D with D's columns (cos t, 0, sin t), (0, 0.5, 0), (0, 0, 1).
  RigidBodySpec spec;
  spec.preset = "orthogonal";
  spec.actuator_misalignment = {t, 0.0, 0.0};
  spec.actuator_scale = {1.0, 0.5, 1.0};
  const RigidBody truth(rigid_body_params(spec));
  const auto G = truth.G(RigidBody::State::Zero());
  const double J[3] = {0.25, 0.30, 0.20};
  EXPECT_NEAR(G(0, 0), c / J[0], 1e-14);
  EXPECT_NEAR(G(2, 0), sn / J[2], 1e-14);
  EXPECT_EQ(G(1, 0), 0.0);
  EXPECT_NEAR(G(1, 1), 0.5 / J[1], 1e-14);
  EXPECT_NEAR(G(2, 2), 1.0 / J[2], 1e-14);
  // Values out of range, at their paths; the flattened values keep them.
  spec.actuator_scale = {1.0, -0.5, 1.0};
  spec.actuator_misalignment = {0.0, 4.0};
  const std::vector<FieldError> errs = validate(spec, "/s");
  ASSERT_EQ(errs.size(), 2u);
  EXPECT_EQ(errs[0].path, "/s/actuator_scale/1");
  EXPECT_EQ(errs[1].path, "/s/actuator_misalignment");
  EXPECT_NE(errs[1].message.find("one value per actuator (3), got 2"), std::string::npos);
  spec.actuator_scale = {1.0, 0.5, 1.0};
  spec.actuator_misalignment = {t, 0.0, 0.0};
  const RigidBodySpec back = rigid_body_spec(to_values(spec));
  EXPECT_EQ(back.actuator_scale, spec.actuator_scale);
  EXPECT_EQ(back.actuator_misalignment, spec.actuator_misalignment);
  EXPECT_TRUE(rigid_body_spec(to_values(RigidBodySpec{})).actuator_scale.empty());
}

// A scenario's actuator_scale and actuator_misalignment are the simulated plant's; the
// controller keeps the job's model. The model's own values give the same bits as none, and an
// actuator at half effectiveness flies exactly as one with a 50 % loss from t = 0 (without
// limits the two are the same products: halving is exact).
TEST(RigidBody, ActuatorUncertaintyOfAScenarioActsOnTheSimulatedPlantOnly) {
  RigidBodySpec spec;
  spec.preset = "pyramid";
  spec.inertia = {0.25, 0.0, 0.0, 0.0, 0.30, 0.0, 0.0, 0.0, 0.20};
  const auto plant = plant_of(spec);
  ControllerConfig ctl = ControllerConfig::table1(ControllerType::pi_fosmc);
  ctl.switching_gain = 0.05;
  const Scenario plain = scenario();
  const SimulationResult r0 = plant->simulate(ctl, plain);
  Scenario same = plain;
  same.set_true_value("actuator_scale", {1.0, 1.0, 1.0, 1.0});
  same.set_true_value("actuator_misalignment", {0.0, 0.0, 0.0, 0.0});
  const SimulationResult r1 = plant->simulate(ctl, same);
  EXPECT_TRUE(same_bits(r1.metrics.errors.ise, r0.metrics.errors.ise));
  EXPECT_EQ(r1.final_state, r0.final_state);

  Scenario half = plain;
  half.set_true_value("actuator_scale", {1.0, 0.5, 1.0, 1.0});
  Scenario lost = plain;
  Fault f;
  f.actuator = 2;
  f.type = FaultType::loss_of_effectiveness;
  f.fraction = 0.5;
  f.onset = 0.0;
  lost.faults = {f};
  const SimulationResult rh = plant->simulate(ctl, half), rl = plant->simulate(ctl, lost);
  EXPECT_NE(rh.final_state, r0.final_state);
  EXPECT_EQ(rh.final_state, rl.final_state);
  EXPECT_TRUE(same_bits(rh.metrics.errors.ise, rl.metrics.errors.ise));

  Scenario turned = plain;
  turned.set_true_value("actuator_misalignment", {0.0, 0.0, 0.1, 0.0});
  EXPECT_NE(plant->simulate(ctl, turned).final_state, r0.final_state);
  // Per actuator: the plant's m values, or an error at the key.
  Scenario wrong = plain;
  wrong.set_true_value("actuator_scale", {1.0, 1.0});
  EXPECT_THROW(plant->simulate(ctl, wrong), InputError);
  const PlantKind& k = *find_plant_kind("rigid_body");
  const std::vector<FieldError> errs =
      k.check_true_values(to_values(spec), {{"actuator_scale", {1.0, 1.0}}}, "/scenarios/0");
  ASSERT_EQ(errs.size(), 1u);
  EXPECT_EQ(errs[0].path, "/scenarios/0/actuator_scale");
  EXPECT_NE(errs[0].message.find("one value per actuator of the rigid_body (4), got 2"),
            std::string::npos)
      << errs[0].message;
  // The simulated plant's actuators must still span R³ (a wheel at effectiveness 0 on the
  // orthogonal triad leaves a plane): refused at the key, not thrown from the simulation.
  const PlantKind& k3 = *find_plant_kind("rigid_body");
  RigidBodySpec triad;
  triad.preset = "orthogonal";
  const std::vector<FieldError> flat =
      k3.check_true_values(to_values(triad), {{"actuator_scale", {1.0, 1.0, 0.0}}}, "/scenarios/0");
  ASSERT_EQ(flat.size(), 1u);
  EXPECT_EQ(flat[0].path, "/scenarios/0/actuator_scale");
  EXPECT_NE(flat[0].message.find("no longer span R³"), std::string::npos) << flat[0].message;
  // Recoverability asks the simulated plant: the pyramid's wheel 1 at effectiveness 0 with
  // wheel 2 lost leaves two axes, though the model's four wheels less one would span R³.
  Scenario dead = plain;
  dead.set_true_value("actuator_scale", {0.0, 1.0, 1.0, 1.0});
  dead.faults = {f};
  dead.faults[0].fraction = 1.0;
  EXPECT_FALSE(plant->recoverable(dead));
  dead.true_values.clear();
  EXPECT_TRUE(plant->recoverable(dead));
  // The multirotor has actuator_scale (its rotors), not a misalignment.
  const PlantKind& mr = *find_plant_kind("multirotor");
  EXPECT_NE(mr.find_uncertain("actuator_scale"), nullptr);
  EXPECT_EQ(mr.find_uncertain("actuator_misalignment"), nullptr);
}

namespace {

Fault wheel_fault(int actuator, FaultType type, double amount) {
  Fault f;
  f.actuator = actuator;
  f.type = type;
  f.onset = 1.0;
  if (type == FaultType::stuck) f.value = amount;
  if (type == FaultType::loss_of_effectiveness) f.fraction = amount;
  return f;
}

bool recoverable_with(const AnyPlant& p, std::vector<Fault> faults) {
  Scenario s = scenario();
  s.faults = std::move(faults);
  return p.recoverable(s);
}

}  // namespace

// By hand (docs/model.md, "Which single failures are recoverable"): any 3 of the pyramid's 4
// axes are independent (the determinant of three of them is ±2 cos²β sin β ≠ 0 for
// 0 < β < 90°), so one stuck or failed wheel of four leaves full rank and two do not; the
// orthogonal triad has no spare; nasa's skewed wheel stands in for any one of the three.
TEST(RigidBody, RecoverabilityOfWheelFaultsCheckedByHand) {
  const auto make = [](const std::string& preset) {
    RigidBodySpec s;
    s.preset = preset;
    return plant_of(s);
  };
  const auto pyramid = make("pyramid"), orthogonal = make("orthogonal"), nasa = make("nasa");
  for (int j = 1; j <= 4; ++j) {
    EXPECT_TRUE(recoverable_with(*pyramid, {wheel_fault(j, FaultType::stuck, 0.002)})) << j;
    EXPECT_TRUE(
        recoverable_with(*pyramid, {wheel_fault(j, FaultType::loss_of_effectiveness, 1.0)}));
    EXPECT_TRUE(recoverable_with(*nasa, {wheel_fault(j, FaultType::loss_of_effectiveness, 1.0)}));
  }
  EXPECT_FALSE(recoverable_with(*pyramid, {wheel_fault(1, FaultType::stuck, 0.0),
                                           wheel_fault(3, FaultType::loss_of_effectiveness, 1.0)}));
  for (int j = 1; j <= 3; ++j) {
    EXPECT_FALSE(recoverable_with(*orthogonal, {wheel_fault(j, FaultType::stuck, 0.0)})) << j;
    EXPECT_TRUE(
        recoverable_with(*orthogonal, {wheel_fault(j, FaultType::loss_of_effectiveness, 0.5)}));
  }
}

// By hand: the default pyramid's axes are (±1, ±1, 1)/√3, and wheels 2, 3, 4 cancel wheel 1's
// torque v·â1 only with u = (−v, v, −v): each needs |v| of its own limit. So with every wheel
// limited to 0.1 N·m, wheel 1 stuck at |v| < 0.1 is recoverable and at 0.1 (or beyond, which
// its limit cuts to 0.1) it is not, though the three left still span R³. The rank alone said
// recoverable for every v.
TEST(RigidBody, AStuckWheelIsRecoverableOnlyWhenTheOthersCanCancelItWithinTheirLimits) {
  const auto make = [](std::vector<double> max) {
    RigidBodySpec s;
    s.preset = "pyramid";
    s.max = std::move(max);
    return plant_of(s);
  };
  const auto limited = make({0.1});
  EXPECT_TRUE(recoverable_with(*limited, {wheel_fault(1, FaultType::stuck, 0.09)}));
  EXPECT_TRUE(recoverable_with(*limited, {wheel_fault(1, FaultType::stuck, -0.095)}));
  EXPECT_FALSE(recoverable_with(*limited, {wheel_fault(1, FaultType::stuck, 0.1)}));
  EXPECT_FALSE(recoverable_with(*limited, {wheel_fault(1, FaultType::stuck, 5.0)}));
  for (int j = 2; j <= 4; ++j) {
    EXPECT_TRUE(recoverable_with(*limited, {wheel_fault(j, FaultType::stuck, 0.09)})) << j;
    EXPECT_FALSE(recoverable_with(*limited, {wheel_fault(j, FaultType::stuck, -0.1)})) << j;
  }
  // A loss on a wheel that must cancel shrinks its range to (1 − ρ)·0.1: 0.05 with ρ = 0.5.
  EXPECT_TRUE(recoverable_with(*limited, {wheel_fault(1, FaultType::stuck, 0.04),
                                          wheel_fault(2, FaultType::loss_of_effectiveness, 0.5)}));
  EXPECT_FALSE(recoverable_with(*limited, {wheel_fault(1, FaultType::stuck, 0.06),
                                           wheel_fault(2, FaultType::loss_of_effectiveness, 0.5)}));
  // Per-wheel limits: wheel 1 may deliver 0.2, more than the others can cancel.
  const auto strong_first = make({0.2, 0.1, 0.1, 0.1});
  EXPECT_TRUE(recoverable_with(*strong_first, {wheel_fault(1, FaultType::stuck, 0.09)}));
  EXPECT_FALSE(recoverable_with(*strong_first, {wheel_fault(1, FaultType::stuck, 0.15)}));
  // The scenario's saturation limits every wheel, the stuck one's output included.
  Scenario s = scenario();
  s.faults = {wheel_fault(1, FaultType::stuck, 0.09)};
  s.saturation.values = {0.05};
  EXPECT_FALSE(limited->recoverable(s));
  s.saturation.values = {0.1, 0.05, 0.1, 0.1};  // wheel 2 cannot give the 0.09 needed
  EXPECT_FALSE(limited->recoverable(s));
  // Without limits any stuck torque can be cancelled.
  EXPECT_TRUE(recoverable_with(*make({}), {wheel_fault(1, FaultType::stuck, 1e6)}));
}

// By hand: quad_x's rotors hold hover with zero torque only with all four thrusts equal (roll
// and pitch balance give T1 = T3 and T2 = T4, yaw then T1 = T2), so T = m g / 4 = 3.679 N each,
// with no freedom. A loss ρ leaves the rotor (1 − ρ)·8 N, enough while ρ < 1 − 3.679/8 = 0.540;
// a stuck rotor is recoverable only at exactly the hover thrust; a failed rotor never.
TEST(Multirotor, RecoverabilityOfQuadRotorFaultsCheckedByHand) {
  const auto quad = plant_of(MultirotorSpec{});
  const double Th = 1.5 * 9.81 / 4.0;
  for (int i = 1; i <= 4; ++i) {
    EXPECT_TRUE(recoverable_with(*quad, {wheel_fault(i, FaultType::loss_of_effectiveness, 0.3)}));
    EXPECT_TRUE(recoverable_with(*quad, {wheel_fault(i, FaultType::loss_of_effectiveness, 0.53)}));
    EXPECT_FALSE(recoverable_with(*quad, {wheel_fault(i, FaultType::loss_of_effectiveness, 0.55)}));
    EXPECT_FALSE(recoverable_with(*quad, {wheel_fault(i, FaultType::loss_of_effectiveness, 1.0)}));
    EXPECT_TRUE(recoverable_with(*quad, {wheel_fault(i, FaultType::stuck, Th)})) << i;
    EXPECT_FALSE(recoverable_with(*quad, {wheel_fault(i, FaultType::stuck, 3.0)})) << i;
  }
}

// A scenario's per-actuator saturation names the plant's m limits; the kernel's columns past m
// have none (Saturation::limit past the list), so a limit never reached counts no sample and an
// active one holds each wheel to its own.
TEST(RigidBody, PerActuatorSaturationNamesTheRealActuatorsOnly) {
  RigidBodySpec spec;
  spec.preset = "nasa";
  const auto plant = plant_of(spec);
  ControllerConfig c = ControllerConfig::table1(ControllerType::fosmc);
  c.switching_gain = 0.01;
  Scenario s = scenario(2.0);
  s.saturation = std::vector<double>{100, 100, 100, 100};
  SimulationOptions o;
  o.record_every = 1;
  EXPECT_EQ(plant->simulate(c, s, o).metrics.errors.saturation_fraction, 0.0);
  s.saturation = std::vector<double>{0.02, 0.03, 0.04, 0.05};
  const SimulationResult r = plant->simulate(c, s, o);
  EXPECT_GT(r.metrics.errors.saturation_fraction, 0.0);
  for (std::size_t i = 0; i < r.trajectory.rows(); ++i) {
    ASSERT_EQ(r.trajectory.u(i).size(), 4u);
    for (std::size_t j = 0; j < 4; ++j)
      EXPECT_LE(std::abs(r.trajectory.u(i)[j]), s.saturation.values[j]) << i << " " << j;
  }
  s.saturation = std::vector<double>{0.02, 0.03};  // two limits for four wheels
  EXPECT_THROW(plant->simulate(c, s, o), InputError);
}
