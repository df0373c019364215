// The hexarotor's attitude plant: f and G against hand-computed values, G G⁺ = I, hover held
// without a command, the hover offset under rotor faults, every lane of its kernel giving the
// scalar bits, and the recoverability rule (SPEC §12 plus hover within the rotor limits) on a
// recoverable and an unrecoverable rotor fault checked by hand; and a job that only another
// plant accepts, rejected at its JSON path.
#include <gtest/gtest.h>

#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <fstream>
#include <nlohmann/json.hpp>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "ftc/sim/controller.hpp"
#include "ftc/sim/hexarotor.hpp"
#include "ftc/sim/input_error.hpp"
#include "ftc/sim/isa.hpp"
#include "ftc/sim/plants.hpp"
#include "ftc/sim/simulation.hpp"
#include "ftc/tune/job/job.hpp"
#include "same_bits.hpp"

using namespace ftc;
using namespace ftc::sim;

namespace {

PlantSpec hexarotor_spec() {
  PlantSpec spec;
  spec.model = "hexarotor";
  return spec;
}

Scenario hover_scenario(double duration = 4.0) {
  Scenario s;
  s.name = "hover";
  s.duration = duration;
  s.initial_state = {0.2, -0.15, 0.1, 0.0, 0.0, 0.0};
  s.disturbance = {{1, Shape::sin, 0.2, 1.0, 0.0}, {3, Shape::cos, 0.1, 2.0, 0.0}};
  return s;
}

Fault rotor_loss(int rotor, double fraction, double onset) {
  Fault f;
  f.actuator = rotor;
  f.type = FaultType::loss_of_effectiveness;
  f.fraction = fraction;
  f.onset = onset;
  return f;
}

using ftc::testing::same_bits;

}  // namespace

// Typhoon H480 defaults: Ix, Iy, Iz = 0.011, 0.015, 0.021 kg·m², l = 0.243 m, κ = 0.06 m.
TEST(Hexarotor, MatchesHandComputedTerms) {
  const Hexarotor h;
  Hexarotor::State x;
  x << 0.3, -0.2, 0.1, 0.1, 0.2, 0.3;
  const Vec3 f = h.f(x);
  // kx q r = (0.015 − 0.021)/0.011 · 0.06, ky p r = (0.021 − 0.011)/0.015 · 0.03,
  // kz p q = (0.011 − 0.015)/0.021 · 0.02.
  EXPECT_NEAR(f[0], -0.0327272727272727, 1e-15);
  EXPECT_NEAR(f[1], 0.02, 1e-15);
  EXPECT_NEAR(f[2], -0.0038095238095238, 1e-15);
  const Mat<3, 6> G = h.G(x);
  // Rotor 1 at 30°, clockwise: roll l sin 30° / Ix, pitch −l cos 30° / Iy, yaw +κ / Iz.
  EXPECT_NEAR(G(0, 0), 0.243 * 0.5 / 0.011, 1e-12);
  EXPECT_NEAR(G(1, 0), -0.243 * std::sqrt(3.0) / 2.0 / 0.015, 1e-12);
  EXPECT_NEAR(G(2, 0), 0.06 / 0.021, 1e-12);
  // Rotor 2 at 90°, counter-clockwise: no pitch, yaw −κ / Iz.
  EXPECT_NEAR(G(0, 1), 0.243 / 0.011, 1e-12);
  EXPECT_NEAR(G(1, 1), 0.0, 1e-15);
  EXPECT_NEAR(G(2, 1), -0.06 / 0.021, 1e-12);
  // Equal thrusts give no torque.
  EXPECT_LT((G * Vec<6>::Ones()).norm(), 1e-12);
  EXPECT_LT((G * h.G_pinv(x) - Mat<3, 3>::Identity()).norm(), 1e-12);
  EXPECT_LT((h.G_pinv(x) - Hexarotor::right_inverse(G)).norm(), 1e-9);
  EXPECT_NEAR(h.hover_thrust(), 2.02 * 9.81 / 6.0, 1e-12);
}

TEST(Hexarotor, RejectsNonPhysicalParametersByName) {
  const auto message = [](const HexarotorParams& p) -> std::string {
    try {
      const Hexarotor h(p);
    } catch (const InputError& e) {
      return e.what();
    }
    return "";
  };
  HexarotorParams p;
  p.inertia[1] = 0.0;
  EXPECT_NE(message(p).find("/inertia/1"), std::string::npos) << message(p);
  HexarotorParams weak;
  weak.max_thrust = 3.0;  // 6 × 3 N < 2.02 kg × 9.81 m/s²
  EXPECT_NE(message(weak).find("/max_thrust"), std::string::npos) << message(weak);
  EXPECT_EQ(message(HexarotorParams{}), "");
}

// A failed rotor (loss of effectiveness 1) gives no thrust: its applied command is −T_h, not
// 0, from its onset on; before it, the commands stay within the rotor's [−T_h, T_max − T_h].
TEST(Hexarotor, FailedRotorLosesItsHoverThrust) {
  const auto plant = make_plant(hexarotor_spec());
  Scenario s = hover_scenario(2.0);
  s.faults = {rotor_loss(2, 1.0, 1.0)};
  SimulationOptions o;
  o.record_every = 1;
  const SimulationResult r =
      plant->simulate(ControllerConfig::table1(ControllerType::pi_fosmc), s, o);
  const Trajectory& tr = r.trajectory;
  const Hexarotor h;
  const double Th = h.hover_thrust(), Tmax = h.params().max_thrust;
  for (std::size_t k = 0; k < tr.rows(); ++k) {
    const std::span<const double> u = tr.u(k);
    for (int j = 0; j < 6; ++j) {
      EXPECT_GE(u[j], -Th) << "t = " << tr.t(k);
      EXPECT_LE(u[j], Tmax - Th) << "t = " << tr.t(k);
    }
    if (tr.t(k) >= 1.0) {
      EXPECT_EQ(u[1], -Th) << "t = " << tr.t(k);
    }
  }
}

// Every lane of a pack, on every instruction set, gives the bits of the same simulation alone,
// and the Controller loop (sim::simulate) gives them too.
TEST(Hexarotor, EveryLaneGivesTheScalarBits) {
  const auto plant = make_plant(hexarotor_spec());
  for (ControllerType type : kAllControllerTypes)
    for (Isa isa : supported_isas()) {
      const int n = lane_width(isa) + 1;
      std::vector<ControllerConfig> configs(n);
      std::vector<Scenario> scenarios(n, hover_scenario());
      std::vector<SimulationOptions> options(n);
      std::vector<PackTask> tasks;
      for (int l = 0; l < n; ++l) {
        configs[l] = ControllerConfig::table1(type);
        configs[l].switching_gain *= 1.0 + 0.1 * l;
        configs[l].Kp = 1.0 + 4.0 * l;
        scenarios[l].faults = {rotor_loss(1 + l % 6, 0.2 + 0.1 * l, 1.0 + 0.2 * l)};
        if (l % 2 == 1)
          scenarios[l].set_true_value("inertia", {0.011 * (1.0 + 0.05 * l), 0.015, 0.021});
        if (l % 3 == 2) scenarios[l].saturation = 2.0;
        options[l].record_every = l == 0 ? 0 : 20;
        tasks.push_back({&configs[l], &scenarios[l], &options[l]});
      }
      std::vector<SimulationResult> got(n);
      std::vector<std::string> errors(n);
      plant->simulate_pack(tasks, got, errors, isa);
      for (int l = 0; l < n; ++l) {
        const std::string what = std::string(to_string(type)) + " on " + to_string(isa) +
                                 ", lane " + std::to_string(l);
        ASSERT_EQ(errors[l], "") << what;
        const SimulationResult want = plant->simulate(configs[l], scenarios[l], options[l]);
        EXPECT_EQ(got[l].samples, want.samples) << what;
        for (std::size_t i = 0; i < want.final_state.size(); ++i)
          EXPECT_TRUE(same_bits(got[l].final_state[i], want.final_state[i])) << what;
        EXPECT_TRUE(same_bits(got[l].metrics.errors.ise, want.metrics.errors.ise)) << what;
        EXPECT_TRUE(same_bits(got[l].metrics.control_tv, want.metrics.control_tv)) << what;
        ASSERT_EQ(got[l].trajectory.values.size(), want.trajectory.values.size()) << what;
        for (std::size_t i = 0; i < want.trajectory.values.size(); ++i)
          ASSERT_TRUE(same_bits(got[l].trajectory.values[i], want.trajectory.values[i])) << what;
      }
    }
  // The runtime's Controller loop on the class gives the lane's bits (no model mismatch).
  const Hexarotor h;
  Scenario s = hover_scenario();
  s.faults = {rotor_loss(3, 0.5, 1.0)};
  for (ControllerType type : kAllControllerTypes) {
    const ControllerConfig cfg = ControllerConfig::table1(type);
    auto c = make_controller(cfg, h, s.sample_time);
    const SimulationResult a = simulate(h, *c, s);
    const SimulationResult b = plant->simulate(cfg, s);
    for (std::size_t i = 0; i < a.final_state.size(); ++i)
      EXPECT_TRUE(same_bits(a.final_state[i], b.final_state[i])) << to_string(type);
    EXPECT_TRUE(same_bits(a.metrics.errors.ise, b.metrics.errors.ise)) << to_string(type);
  }
}

// By hand (docs/model.md): hover needs Σ T = m g = 19.816 N and zero torque.
// - Rotor 1 at half effectiveness: all six at T_h = 3.3027 N still balance, rotor 1 well below
//   its reduced 9.617 N; the largest smallest margin is T_h itself (the smallest thrust of six
//   summing to m g is at most m g / 6). Recoverable.
// - Rotor 1 failed (no thrust): zero roll, pitch and yaw torque with T1 = 0 force the opposite
//   rotor 4 to 0 as well (the real and imaginary parts of Σ T_i e^{iα_i} = 0 and Σ σ_i T_i = 0
//   give 3 T4 = 0), so rotor 4 sits at its lower limit and cannot push the attitude back in
//   the direction that needs less of it: margin 0. G without column 1 still has rank 3, which
//   is why the rank rule alone would call it recoverable. Unrecoverable.
TEST(Hexarotor, RecoverabilityOfRotorFaultsCheckedByHand) {
  const Hexarotor h;
  const std::array<bool, 6> none_stuck{};
  const std::array<double, 6> at{};
  std::array<double, 6> lost{};
  lost[0] = 0.5;
  EXPECT_NEAR(h.trim_margin(none_stuck, at, lost), 2.02 * 9.81 / 6.0, 1e-9);
  lost[0] = 1.0;
  EXPECT_NEAR(h.trim_margin(none_stuck, at, lost), 0.0, 1e-9);
  EXPECT_FALSE(h.trim_feasible(none_stuck, at, lost));

  const auto plant = make_plant(hexarotor_spec());
  Scenario s = hover_scenario();
  s.faults = {rotor_loss(1, 0.5, 1.0)};
  EXPECT_TRUE(plant->recoverable(s));
  s.faults = {rotor_loss(1, 1.0, 1.0)};
  EXPECT_FALSE(plant->recoverable(s));
  Fault stuck;
  stuck.actuator = 4;
  stuck.type = FaultType::stuck;
  stuck.value = 0.0;  // a rotor stuck at zero thrust: failed as well
  s.faults = {stuck};
  EXPECT_FALSE(plant->recoverable(s));
  stuck.value = h.hover_thrust();  // stuck at its hover thrust: the others can still balance
  s.faults = {stuck};
  EXPECT_TRUE(plant->recoverable(s));
}

// A rotor stuck at T1: hover with zero torque needs the opposite rotor at T1 too and leaves the
// other four m g / 2 − T1 to share (docs/model.md), so it is recoverable for 0 < T1 < m g / 2
// only; and with a scenario's saturation the rotors' range narrows to T_h ± L.
TEST(Hexarotor, StuckRotorIsRecoverableOnlyBelowHalfTheWeight) {
  const auto plant = make_plant(hexarotor_spec());
  const double half_weight = 2.02 * 9.81 / 2.0;
  Scenario s = hover_scenario();
  Fault stuck;
  stuck.actuator = 1;
  stuck.type = FaultType::stuck;
  for (const auto& [value, recoverable] :
       {std::pair{0.0, false}, std::pair{1e-3, true}, std::pair{0.999 * half_weight, true},
        std::pair{1.001 * half_weight, false}, std::pair{12.0, false}}) {
    stuck.value = value;
    s.faults = {stuck};
    EXPECT_EQ(plant->recoverable(s), recoverable) << "stuck at " << value << " N";
  }
  // The opposite rotor must match a rotor stuck at 6 N, so a limit of 2 N about hover (3.30 N)
  // leaves it short: 6 N is out of its range [1.30, 5.30] N.
  stuck.value = 6.0;
  s.faults = {stuck};
  EXPECT_TRUE(plant->recoverable(s));
  s.saturation = 2.0;
  EXPECT_FALSE(plant->recoverable(s));
}

TEST(Hexarotor, RejectsAFaultOnRotorSeven) {
  const auto plant = make_plant(hexarotor_spec());
  Scenario s = hover_scenario();
  s.faults = {rotor_loss(7, 0.5, 1.0)};
  try {
    plant->simulate(ControllerConfig::table1(ControllerType::pi_fosmc), s);
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("/faults/0/actuator"), std::string::npos) << e.what();
  }
}

// PI-FOSMC with the gains jobs/hexarotor.json tunes (Kp = 1, Ki = 50) levels the hexarotor
// from (0.2, −0.15, 0.1) rad under the disturbance and through a 40 % loss of rotor 1 at 1 s
// (which also takes 40 % of that rotor's hover thrust) by 4 s.
TEST(Hexarotor, PiFosmcLevelsItThroughARotorLoss) {
  const auto plant = make_plant(hexarotor_spec());
  Scenario s = hover_scenario();
  s.faults = {rotor_loss(1, 0.4, 1.0)};
  ControllerConfig c = ControllerConfig::table1(ControllerType::pi_fosmc);
  c.Kp = 1.0;
  c.Ki = 50.0;
  const SimulationResult r = plant->simulate(c, s);
  ASSERT_FALSE(r.metrics.diverged);
  EXPECT_LT(std::abs(r.final_state[0]) + std::abs(r.final_state[1]) + std::abs(r.final_state[2]),
            0.01);
}

// A job that is fine for one plant and wrong for another gets the error at its JSON path (exit
// 2 through the CLI): a fault on rotor 7 of six, a true inertia or an ensemble inertia scale for
// the arm, which has no parameter "inertia".
TEST(HexarotorJob, RejectsWhatOnlyAnotherPlantAccepts) {
  const auto errors_of = [](const nlohmann::json& j) {
    try {
      tune::parse_job(j, "job.json");
    } catch (const InputError& e) {
      return e.errors();
    }
    return std::vector<FieldError>{};
  };
  const auto has = [](const std::vector<FieldError>& errs, const std::string& path,
                      const std::string& message) {
    for (const FieldError& e : errs)
      if (e.path == path && e.message.find(message) != std::string::npos) return true;
    return false;
  };
  const auto read = [](const std::string& name) {
    std::ifstream in(std::string(FTC_SOURCE_DIR) + "/jobs/" + name);
    return nlohmann::json::parse(in);
  };
  nlohmann::json hex = read("hexarotor.json");
  EXPECT_TRUE(errors_of(hex).empty());
  hex["scenarios"][0]["faults"][0]["actuator"] = 7;
  EXPECT_TRUE(has(errors_of(hex), "/scenarios/0/faults/0/actuator", "1..6"));

  nlohmann::json arm = read("manipulator.json");
  arm["scenarios"][0]["inertia"] = {0.1, 0.1};
  EXPECT_TRUE(has(errors_of(arm), "/scenarios/0/inertia",
                  "does not declare inertia uncertain (its uncertain parameters: none)"));
  arm = read("manipulator.json");
  arm["ensemble"] = {{"count", 4}, {"seed", 1}, {"inertia_scale", {{"uniform", {0.8, 1.2}}}}};
  EXPECT_TRUE(has(errors_of(arm), "/ensemble/inertia_scale", "declares no uncertain parameters"));
  // The same keys are fine for the hexarotor, which has one.
  hex = read("hexarotor.json");
  hex["scenarios"][0]["inertia"] = {0.012, 0.015, 0.021};
  hex["ensemble"] = {{"count", 4}, {"seed", 1}, {"inertia_scale", {{"uniform", {0.8, 1.2}}}}};
  EXPECT_TRUE(errors_of(hex).empty());
}
