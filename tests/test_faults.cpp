#include <gtest/gtest.h>

#include <cmath>

#include "ftc/sim/disturbance.hpp"
#include "ftc/sim/faults.hpp"
#include "ftc/sim/scenario.hpp"

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

TEST(Faults, ValidationNamesFields) {
  Fault f = make(FaultType::loss_of_effectiveness, 5, -1.0);
  f.fraction = 1.5;
  const auto errs = f.validate("/f");
  ASSERT_EQ(errs.size(), 3u);
  EXPECT_EQ(errs[0].path, "/f/actuator");
  EXPECT_EQ(errs[1].path, "/f/onset");
  EXPECT_EQ(errs[2].path, "/f/fraction");
}

TEST(Disturbance, PaperDisturbance) {
  const Disturbance d(Scenario::paper().disturbance);
  const double t = 1.7;
  const Vec3 v = d(t);
  EXPECT_DOUBLE_EQ(v[0], 0.5 * std::sin(t));
  EXPECT_DOUBLE_EQ(v[1], 0.5 * std::cos(2 * t));
  EXPECT_DOUBLE_EQ(v[2], 0.5 * std::sin(3 * t));
}

TEST(Disturbance, PhasorEvaluationMatchesDirectOne) {
  const Disturbance d({{2, Shape::sin, 1.0, 2.0, 0.5},
                       {2, Shape::cos, 0.25, 1.0, 0.0},
                       {3, Shape::cos, 0.7, 3.0, -1.0}});
  std::vector<Phasor> p = d.phasors(1e-3);
  for (Phasor& q : p) q.anchor(2.5);
  EXPECT_EQ(d(p), d(2.5));  // anchored: the same libm values
  for (Phasor& q : p) q.advance();
  EXPECT_TRUE(d(p).isApprox(d(2.501), 1e-14));
}

TEST(Faults, PhasorEffectMatchesDirectOne) {
  const Scenario s = Scenario::paper();
  const FaultSet set(s.faults, std::nullopt);
  std::vector<Phasor> p = set.phasors(5e-4);
  for (Phasor& q : p) q.anchor(25.0);
  for (int n = 1; n <= 10; ++n) {
    for (Phasor& q : p) q.advance();
    const double t = 25.0 + n * 5e-4;
    EXPECT_TRUE(set.effect(t, p).offset.isApprox(set.effect(t).offset, 1e-14));
    EXPECT_EQ(set.effect(t, p).gain, set.effect(t).gain);
  }
}

TEST(Disturbance, TermsOnOneAxisAddWithPhase) {
  const Disturbance d({{2, Shape::sin, 1.0, 2.0, 0.5}, {2, Shape::cos, 0.25, 1.0, 0.0}});
  const Vec3 v = d(0.3);
  EXPECT_EQ(v[0], 0.0);
  EXPECT_DOUBLE_EQ(v[1], std::sin(2.0 * 0.3 + 0.5) + 0.25 * std::cos(0.3));
}
