#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <span>

#include "controllers/adaptive_neural_pi_fosmc.hpp"
#include "controllers/laws.hpp"
#include "ftc/sim/controller.hpp"
#include "ftc/sim/simulation.hpp"
#include "ftc/sim/spacecraft.hpp"

using namespace ftc::sim;

namespace {

SimulationResult run(const ControllerConfig& cfg, std::int64_t record_every = 0) {
  const Spacecraft plant;
  const Scenario s = Scenario::paper();
  auto c = make_controller(cfg, plant, s.sample_time);
  SimulationOptions o;
  o.record_every = record_every;
  return simulate(plant, *c, s, o);
}

// Inputs for single-step checks.
const Vec3 kX1(0.2, -0.1, 0.4), kX2(-0.3, 0.5, 0.1), kA(0.7, -0.2, 0.3);
constexpr double kTs = 1e-3;

Vec3 sgn_pow(const Vec3& x, double a) {
  Vec3 r;
  for (int i = 0; i < 3; ++i) r[i] = (x[i] > 0 ? 1 : -1) * std::pow(std::abs(x[i]), a);
  return r;
}
Vec3 tanh_half(const Vec3& s, double theta) {
  return Vec3(std::tanh(theta * s[0] / 2), std::tanh(theta * s[1] / 2),
              std::tanh(theta * s[2] / 2));
}

}  // namespace

class EveryController : public ::testing::TestWithParam<ControllerType> {};

TEST_P(EveryController, KeepsAttitudeErrorSmallThroughFaults) {
  const SimulationResult r = run(ControllerConfig::table1(GetParam()), 1);
  ASSERT_FALSE(r.metrics.diverged);
  ASSERT_EQ(r.trajectory.rows(), 30000u);
  double worst = 0.0, at = 0.0;
  for (std::size_t k = 0; k < r.trajectory.rows(); ++k) {
    const double e = Eigen::Map<const Vec3>(r.trajectory.x(k).data()).norm();
    if (r.trajectory.t(k) >= 5.0 && e > worst) {
      worst = e;
      at = r.trajectory.t(k);
    }
  }
  EXPECT_LT(worst, 0.05) << "at t = " << at;
}

TEST_P(EveryController, StepWithGivenDriftEqualsStepComputingIt) {
  const Spacecraft plant;
  auto a = make_controller(ControllerConfig::table1(GetParam()), plant, kTs);
  auto b = make_controller(ControllerConfig::table1(GetParam()), plant, kTs);
  const State x = (State() << kX1, kX2).finished();
  const Vec3 f = plant.f(x);
  for (int k = 0; k < 3; ++k)
    EXPECT_EQ(a->step(k * kTs, kX1, kX2, kA),
              b->step(Measurement<3>{k * kTs, kX1, kX2, kA, &f, &plant}));
}

// A drift of another plant than the controller's model (a simulation with model mismatch) is
// not used: the model-based controllers evaluate their own model.
TEST_P(EveryController, DriftOfAnotherPlantIsIgnored) {
  const Spacecraft model, other(SpacecraftParams{{22.0, 15.3, 16.5}, 1.1e-3});
  auto a = make_controller(ControllerConfig::table1(GetParam()), model, kTs);
  auto b = make_controller(ControllerConfig::table1(GetParam()), model, kTs);
  const State x = (State() << kX1, kX2).finished();
  const Vec3 f = other.f(x);
  ASSERT_NE(f, model.f(x));
  for (int k = 0; k < 3; ++k)
    EXPECT_EQ(a->step(k * kTs, kX1, kX2, kA),
              b->step(Measurement<3>{k * kTs, kX1, kX2, kA, &f, &other}));
}

TEST_P(EveryController, ResetRestoresInitialState) {
  const Spacecraft plant;
  auto c = make_controller(ControllerConfig::table1(GetParam()), plant, kTs);
  const Vec4 first = c->step(0, kX1, kX2, kA);
  c->step(kTs, kX1, kX2, kA);
  c->reset();
  EXPECT_EQ(c->step(0, kX1, kX2, kA), first);
}

INSTANTIATE_TEST_SUITE_P(Controllers, EveryController, ::testing::ValuesIn(kAllControllerTypes),
                         [](const ::testing::TestParamInfo<ControllerType>& p) {
                           return std::string(to_string(p.param));
                         });

TEST(PiFosmc, FirstTwoStepsFollowEquations) {
  const Spacecraft plant;
  const ControllerConfig cfg = ControllerConfig::table1(ControllerType::pi_fosmc);
  auto c = make_controller(cfg, plant, kTs);
  const State x = (State() << kX1, kX2).finished();
  const Vec3 f = plant.f(x);
  const double a1 = 0.5625 / (2 - 0.5625);
  const Vec3 C = 9.0 * sgn_pow(kX2, 0.5625) + 10.0 * sgn_pow(kX1, a1);
  const Vec3 sF = kA + C;

  // k = 0: I = ur = 0.
  const Vec4 u0 = c->step(0.0, kX1, kX2, kA);
  EXPECT_TRUE(u0.isApprox(-plant.G_pinv(x) * (f + C), 1e-13));
  // k = 1: I = Ts sF, ur = Ts K sigm(Kp sF).
  const Vec3 I = kTs * sF;
  const Vec3 ur = kTs * 20.0 * tanh_half(20.0 * sF, 1000.0);
  const Vec4 u1 = c->step(kTs, kX1, kX2, kA);
  EXPECT_TRUE(u1.isApprox(-plant.G_pinv(x) * (f + C + (5.0 / 20.0) * I + ur), 1e-13));
}

TEST(Nftsmc, StepFollowsEquation) {
  const Spacecraft plant;
  auto c = make_controller(ControllerConfig::table1(ControllerType::nftsmc), plant, kTs);
  const State x = (State() << kX1, kX2).finished();
  const double pq = 9.0 / 7.0;
  const Vec3 s = kX1 + 10.0 * sgn_pow(kX1, 1.4) + 5.0 * sgn_pow(kX2, pq);
  Vec3 ueq = plant.f(x);
  for (int i = 0; i < 3; ++i)
    ueq[i] += (7.0 / 9.0) / 5.0 * (1 + 1.4 * 10.0 * std::pow(std::abs(kX1[i]), 0.4)) *
              sgn_pow(kX2, 2 - pq)[i];
  const Vec4 expected = -plant.G_pinv(x) * (ueq + 20.0 * tanh_half(s, 1000.0));
  const Vec4 u = c->step(0.0, kX1, kX2, kA);
  EXPECT_TRUE(u.isApprox(expected, 1e-13));
  EXPECT_EQ(c->step(kTs, kX1, kX2, kA), u);  // memoryless
}

TEST(AdaptiveNeuralPiFosmc, FirstTwoStepsFollowEquations) {
  const Spacecraft plant;
  const ControllerConfig cfg = ControllerConfig::table1(ControllerType::adaptive_neural_pi_fosmc);
  AdaptiveNeuralPiFosmc<3, 4> c(cfg, plant, kTs);
  const State x = (State() << kX1, kX2).finished();
  const double a1 = 0.5625 / (2 - 0.5625);
  const Vec3 C = 9.0 * sgn_pow(kX2, 0.5625) + 10.0 * sgn_pow(kX1, a1);
  const Vec3 sF = kA + C;
  const Vec3 sPI0 = 20.0 * sF;

  // k = 0: Ω = I = ur = 0, no model term at all.
  EXPECT_TRUE(c.step(0.0, kX1, kX2, kA).isApprox(-plant.G_pinv(x) * C, 1e-13));
  // After one step: Ka = 15 + Ts |sPI0| / 100, Ω = 0 (W was 0), ur = Ts (15 + 5) sigm(sPI0).
  EXPECT_TRUE(
      c.adaptive_gain().isApprox(Vec3::Constant(15.0) + kTs / 100.0 * sPI0.cwiseAbs(), 1e-14));
  EXPECT_EQ(c.network_output(), Vec3::Zero());
  const Vec3 I = kTs * sF;
  const Vec3 ur = kTs * 20.0 * tanh_half(sPI0, 1000.0);
  EXPECT_TRUE(c.step(kTs, kX1, kX2, kA).isApprox(-plant.G_pinv(x) * (C + 0.25 * I + ur), 1e-13));
  // After the second step Ω = Ts Wᵀψ with W = Ts · 0.1 · ψ sPI0ᵀ, ψ_j = exp(-‖X - c_j 1‖² / 4).
  Vec3 omega = Vec3::Zero();
  for (int j = 0; j < 7; ++j) {
    const double cj = -1.5 + 0.5 * j;
    const double psi = std::exp(-(x.array() - cj).square().sum() / 4.0);
    omega += kTs * psi * (kTs * 0.1 * psi * sPI0);
  }
  EXPECT_TRUE(c.network_output().isApprox(omega, 1e-12));
}

TEST(PiFosmc, UnitKpZeroKiReproducesFosmcBitForBit) {
  ControllerConfig pi = ControllerConfig::table1(ControllerType::pi_fosmc);
  pi.Kp = 1.0;
  pi.Ki = 0.0;
  const SimulationResult a = run(pi, 1);
  const SimulationResult b = run(ControllerConfig::table1(ControllerType::fosmc), 1);
  ASSERT_EQ(a.trajectory.rows(), b.trajectory.rows());
  for (std::size_t k = 0; k < a.trajectory.rows(); ++k) {
    const std::span<const double> ua = a.trajectory.u_d(k), ub = b.trajectory.u_d(k);
    ASSERT_TRUE(std::equal(ua.begin(), ua.end(), ub.begin())) << "sample " << k;
  }
  EXPECT_EQ(a.metrics.errors.ise, b.metrics.errors.ise);
}

TEST(Controllers, ParametersThatMatterChangeTheResult) {
  struct Case {
    ControllerType type;
    double ControllerConfig::*field;
    double value;
  };
  const Case cases[] = {
      {ControllerType::pi_fosmc, &ControllerConfig::Ki, 40.0},
      {ControllerType::pi_fosmc, &ControllerConfig::Kp, 2.0},
      {ControllerType::pi_fosmc, &ControllerConfig::c1, 5.0},
      {ControllerType::pi_fosmc, &ControllerConfig::switching_gain, 40.0},
      {ControllerType::fosmc, &ControllerConfig::alpha2, 0.7},
      {ControllerType::nftsmc, &ControllerConfig::sigma1, 5.0},
      {ControllerType::nftsmc, &ControllerConfig::theta, 50.0},
      {ControllerType::adaptive_neural_pi_fosmc, &ControllerConfig::lambda, 1.0},
      {ControllerType::adaptive_neural_pi_fosmc, &ControllerConfig::weight_rate, 10.0},
  };
  for (const Case& c : cases) {
    ControllerConfig base = ControllerConfig::table1(c.type);
    ControllerConfig changed = base;
    changed.*c.field = c.value;
    const Metrics m0 = run(base).metrics, m1 = run(changed).metrics;
    EXPECT_NE(m0.errors.ise, m1.errors.ise) << to_string(c.type);
    EXPECT_NE(m0.control_tv, m1.control_tv) << to_string(c.type);
  }
}

TEST(Controllers, ConstructionRejectsInvalidParametersByName) {
  const Spacecraft plant;
  ControllerConfig bad = ControllerConfig::table1(ControllerType::pi_fosmc);
  bad.Kp = 0.0;
  bad.alpha2 = 1.2;
  try {
    make_controller(bad, plant, kTs);
    FAIL() << "expected InputError";
  } catch (const ftc::InputError& e) {
    ASSERT_EQ(e.errors().size(), 2u);
    EXPECT_EQ(e.errors()[0].path, "alpha2");
    EXPECT_EQ(e.errors()[1].path, "Kp");
    EXPECT_NE(std::string(e.what()).find("alpha2"), std::string::npos);
  }
  ControllerConfig nf = ControllerConfig::table1(ControllerType::nftsmc);
  nf.p = 8;
  EXPECT_THROW(make_controller(nf, plant, kTs), ftc::InputError);
  nf.p = 9;
  nf.alpha = 1.1;  // must exceed p/q = 1.2857
  EXPECT_THROW(make_controller(nf, plant, kTs), ftc::InputError);
  EXPECT_THROW(make_controller(ControllerConfig{}, plant, 0.0), ftc::InputError);
}
