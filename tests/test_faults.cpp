#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "ftc/sim/disturbance.hpp"
#include "ftc/sim/faults.hpp"
#include "ftc/sim/scenario.hpp"
#include "sincos.hpp"

using namespace ftc::sim;

namespace {
Fault make(FaultType type, int actuator, double onset) {
  Fault f;
  f.type = type;
  f.actuator = actuator;
  f.onset = onset;
  return f;
}
const Vec4 kCommand(2.0, -3.0, 4.0, -5.0);
}  // namespace

TEST(Faults, AbruptProfileSwitchesAtOnset) {
  FaultProfile p;
  EXPECT_EQ(p.rho(-1e-12), 0.0);
  EXPECT_EQ(p.rho(0.0), 1.0);
  EXPECT_EQ(p.rho(5.0), 1.0);
}

TEST(Faults, IncipientProfileRisesExponentially) {
  FaultProfile p{FaultProfileType::incipient, 0.5};
  EXPECT_EQ(p.rho(-0.1), 0.0);
  EXPECT_EQ(p.rho(0.0), 0.0);
  EXPECT_DOUBLE_EQ(p.rho(2.0), 1.0 - std::exp(-1.0));
  EXPECT_NEAR(p.rho(100.0), 1.0, 1e-15);
}

TEST(Faults, BiasAddsOffsetAndCosineAfterOnset) {
  Fault f = make(FaultType::bias, 1, 10.0);
  f.offset = 5.0;
  f.amplitude = 15.0;
  f.frequency = 1.0;
  f.phase = 0.3;
  const FaultSet set({f}, std::nullopt);
  EXPECT_EQ(set.apply(9.999, kCommand), kCommand);
  const double t = 12.5;
  const Vec4 u = set.apply(t, kCommand);
  EXPECT_DOUBLE_EQ(u[0], 2.0 + 5.0 + 15.0 * std::cos(t + 0.3));
  EXPECT_EQ(u.tail<3>(), kCommand.tail<3>());
}

TEST(Faults, LossOfEffectivenessScalesCommand) {
  Fault f = make(FaultType::loss_of_effectiveness, 2, 20.0);
  f.fraction = 0.8;
  const FaultSet set({f}, std::nullopt);
  EXPECT_EQ(set.apply(19.0, kCommand), kCommand);
  const Vec4 u = set.apply(20.0, kCommand);
  EXPECT_NEAR(u[1], 0.2 * -3.0, 1e-15);
  EXPECT_EQ(u[0], kCommand[0]);
}

TEST(Faults, StuckActuatorHoldsValue) {
  Fault f = make(FaultType::stuck, 3, 1.0);
  f.value = 0.7;
  const FaultSet set({f}, std::nullopt);
  EXPECT_EQ(set.apply(0.5, kCommand)[2], 4.0);
  EXPECT_DOUBLE_EQ(set.apply(1.5, kCommand)[2], 0.7);
  EXPECT_DOUBLE_EQ(set.apply(1.5, Vec4(0, 0, -100, 0))[2], 0.7);
}

TEST(Faults, IncipientStuckBlendsTowardValue) {
  Fault f = make(FaultType::stuck, 4, 0.0);
  f.value = 1.0;
  f.profile = {FaultProfileType::incipient, 2.0};
  const FaultSet set({f}, std::nullopt);
  const double rho = 1.0 - std::exp(-2.0 * 0.25);
  EXPECT_NEAR(set.apply(0.25, kCommand)[3], -5.0 + rho * (1.0 - -5.0), 1e-14);
}

TEST(Faults, SeveralFaultsOnOneActuatorAddUp) {
  Fault bias = make(FaultType::bias, 1, 1.0);
  bias.offset = 2.0;
  Fault loe = make(FaultType::loss_of_effectiveness, 1, 2.0);
  loe.fraction = 0.5;
  const FaultSet set({bias, loe}, std::nullopt);
  EXPECT_DOUBLE_EQ(set.apply(1.5, kCommand)[0], 2.0 + 2.0);
  EXPECT_DOUBLE_EQ(set.apply(2.5, kCommand)[0], 2.0 - 0.5 * 2.0 + 2.0);
}

TEST(Faults, SaturationIsAppliedAfterFaults) {
  Fault bias = make(FaultType::bias, 1, 0.0);
  bias.offset = 10.0;
  const FaultSet set({bias}, 3.0);
  const Vec4 u = set.apply(1.0, kCommand);
  EXPECT_EQ(u, Vec4(3.0, -3.0, 3.0, -3.0));
}

// SPEC §17.1's order for every plant: the command is limited, the faults act on what is left,
// and the result is limited again. A weakened actuator then delivers at most (1 − ρ) of its
// limit however hard it is commanded (limiting only after the faults gave min(L, (1 − ρ) u_d)).
TEST(Faults, LimitsActOnTheCommandBeforeAndAfterTheFaults) {
  Fault loss = make(FaultType::loss_of_effectiveness, 2, 0.0);
  loss.fraction = 0.5;
  Fault bias = make(FaultType::bias, 1, 0.0);
  bias.offset = 50.0;
  Fault stuck = make(FaultType::stuck, 3, 0.0);
  stuck.value = 40.0;
  const FaultSet set({loss, bias, stuck}, 30.0);
  const Vec4 u = set.apply(1.0, Vec4(-100.0, 100.0, 0.0, 45.0));
  EXPECT_EQ(u[0], 20.0);   // clamp(−30 + 50): the bias acts on the limited command
  EXPECT_EQ(u[1], 15.0);   // 0.5 · clamp(100), not clamp(0.5 · 100) = 30
  EXPECT_EQ(u[2], 30.0);   // a stuck value beyond the limit is held at it
  EXPECT_EQ(u[3], 30.0);   // no fault: the limit
  // One limit per actuator.
  const FaultSet each({loss}, std::vector<double>{1.0, 8.0, 2.0, 3.0});
  EXPECT_EQ(each.apply(1.0, Vec4(5.0, 100.0, -5.0, 2.5)), Vec4(1.0, 4.0, -2.0, 2.5));
  EXPECT_EQ(each.saturation().limit(1), 8.0);
  EXPECT_EQ(FaultSet({loss}, std::nullopt).saturation().limit(3),
            std::numeric_limits<double>::infinity());
}

// A scenario's saturation: one number, or one per actuator, each at its path.
TEST(Faults, PerActuatorSaturationIsValidatedAtItsPath) {
  Scenario s;
  s.name = "x";
  s.saturation = std::vector<double>{1.0, -2.0, 3.0, 4.0};
  auto has = [](const std::vector<ftc::FieldError>& errs, const std::string& path,
                const std::string& text) {
    for (const auto& e : errs)
      if (e.path == path && e.message.find(text) != std::string::npos) return true;
    return false;
  };
  std::vector<ftc::FieldError> errs = s.validate("/scenarios/0", 3, 4);
  EXPECT_TRUE(has(errs, "/scenarios/0/saturation/1", "> 0"));
  s.saturation = std::vector<double>{1.0, 2.0, 3.0};
  errs = s.validate("/scenarios/0", 3, 4);
  EXPECT_TRUE(has(errs, "/scenarios/0/saturation",
                  "expected one number for every actuator or 4 (one per actuator of the plant's "
                  "4), got 3"));
  s.saturation = std::vector<double>{1.0, 2.0, 3.0, 4.0};
  EXPECT_FALSE(has(s.validate("/scenarios/0", 3, 4), "/scenarios/0/saturation", ""));
}

TEST(Faults, ValidationNamesFields) {
  Fault f = make(FaultType::loss_of_effectiveness, 5, -1.0);
  f.fraction = 1.5;
  const auto errs = f.validate("/f", 4);
  ASSERT_EQ(errs.size(), 3u);
  EXPECT_EQ(errs[0].path, "/f/actuator");
  EXPECT_EQ(errs[1].path, "/f/onset");
  EXPECT_EQ(errs[2].path, "/f/fraction");
}

TEST(Faults, BlockEvaluationMatchesPointwise) {
  Fault bias = make(FaultType::bias, 1, 1.0);
  bias.offset = 5.0;
  bias.amplitude = 15.0;
  bias.frequency = 1.0;
  bias.phase = 0.3;
  bias.profile = {FaultProfileType::incipient, 2.0};
  Fault loe = make(FaultType::loss_of_effectiveness, 2, 2.0);
  loe.fraction = 0.8;
  Fault stuck = make(FaultType::stuck, 1, 3.0);
  stuck.value = -0.5;
  Fault second = make(FaultType::loss_of_effectiveness, 2, 2.5);
  second.fraction = 0.1;
  const FaultSet set({bias, loe, stuck, second}, 4.0);
  // Instants before, at and after each onset, in one block.
  const std::vector<double> t = {0.0, 1.0, 1.5, 2.0, 2.5, 2.75, 3.0, 9.0};
  std::vector<FaultEffect<4>> out(t.size());
  set.evaluate(
      t,
      [&](std::size_t i, std::size_t k) {
        return std::cos(set.faults()[i].frequency * t[k] + set.faults()[i].phase);
      },
      [&](std::size_t k) -> FaultEffect<4>& { return out[k]; });
  for (std::size_t k = 0; k < t.size(); ++k) {
    const FaultEffect<4> e = set.effect<4>(t[k]);
    EXPECT_EQ(out[k].gain, e.gain) << t[k];
    EXPECT_EQ(out[k].offset, e.offset) << t[k];
  }
  // Spot values from the definition: after 3 s actuator 1 is stuck on top of the grown bias,
  // actuator 2 has lost 80 % and then 10 % more.
  const double rho = 1.0 - std::exp(-2.0 * (9.0 - 1.0));
  EXPECT_EQ(out[7].gain, Vec4(0.0, 1.0 - 0.8 - 0.1, 1.0, 1.0));
  EXPECT_DOUBLE_EQ(out[7].offset[0], rho * (5.0 + 15.0 * std::cos(9.3)) - 0.5);
  EXPECT_EQ(out[0].gain, Vec4::Ones());
  EXPECT_EQ(out[0].offset, Vec4::Zero());
}
