#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "ftc/sim/input_error.hpp"
#include "ftc/sim/spacecraft.hpp"
#include "plants/spacecraft_dynamics.hpp"
#include "sincos.hpp"

using namespace ftc::sim;

namespace {

State random_state(std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(-2.0, 2.0);
  State x;
  for (int i = 0; i < 6; ++i) x[i] = u(rng);
  return x;
}

// Appendix B transcribed independently of the implementation (sin(2x) called directly).
Vec3 paper_f(const State& x, double Ix, double Iy, double Iz, double w) {
  using std::cos;
  using std::sin;
  const double x1 = x[0], x2 = x[1], x3 = x[2], x4 = x[3], x5 = x[4], x6 = x[5];
  const double w2 = w * w;
  const double f1 =
      w * x6 * cos(x3) * cos(x2) - w * x5 * sin(x3) * sin(x2) +
      (Iy - Iz) / Ix *
          (x5 * x6 + w * x5 * cos(x1) * sin(x3) * sin(x2) + w * x5 * cos(x3) * sin(x1) +
           w * x6 * cos(x3) * cos(x1) + 0.5 * w2 * sin(2 * x3) * cos(x1) * cos(x1) * sin(x2) +
           0.5 * w2 * cos(x3) * cos(x3) * sin(2 * x1) - w * x6 * sin(x3) * sin(x2) * sin(x1) -
           0.5 * w2 * sin(x2) * sin(x2) * sin(x3) * sin(x3) * sin(2 * x1) -
           w * sin(2 * x2) * sin(x2) * sin(x1) * sin(x1) -
           1.5 * w2 * cos(x2) * cos(x2) * sin(2 * x1));
  const double f2 =
      w * x6 * sin(x3) * cos(x1) + w * x4 * cos(x3) * sin(x1) +
      w * x6 * cos(x3) * sin(x2) * sin(x1) + w * x5 * sin(x3) * cos(x2) * sin(x1) +
      w * x4 * sin(x3) * sin(x2) * cos(x1) +
      (Iz - Ix) / Iy *
          (x4 * x6 + w * x4 * cos(x1) * sin(x3) * sin(x2) + w * x4 * cos(x3) * sin(x2) * sin(x1) -
           w * x6 * sin(x3) * cos(x2) - 0.5 * w2 * sin(2 * x2) * sin(x3) * sin(x3) * cos(x1) -
           0.5 * w2 * cos(x2) * sin(x1) * sin(2 * x3) + 1.5 * w2 * sin(2 * x2) * cos(x1));
  const double f3 =
      w * x4 * sin(x1) * sin(x3) * sin(x2) - w * x6 * cos(x1) * cos(x3) * sin(x2) -
      w * x5 * cos(x1) * sin(x3) * cos(x2) + w * x6 * sin(x3) * sin(x1) -
      w * x4 * cos(x3) * cos(x1) +
      (Ix - Iy) / Iz *
          (x4 * x5 + w * x4 * cos(x3) * cos(x1) - w * x4 * sin(x3) * sin(x2) * sin(x1) -
           w * x5 * sin(x3) * cos(x2) - 0.5 * w2 * sin(2 * x3) * cos(x2) * cos(x1) -
           0.5 * w2 * sin(x3) * sin(x3) * sin(x1) * sin(2 * x2) - 1.5 * w2 * sin(2 * x2) * sin(x1));
  return Vec3(f1, f2, f3);
}

}  // namespace

TEST(Spacecraft, DriftIsZeroAtOrigin) {
  const Spacecraft sc;
  EXPECT_EQ(sc.f(State::Zero()), Vec3::Zero());
}

TEST(Spacecraft, ZeroOrbitalRateLeavesEulerGyroscopicTerms) {
  SpacecraftParams p;
  p.orbital_rate = 0.0;
  const Spacecraft sc(p);
  const double kx = (17.0 - 15.0) / 20.0, ky = (15.0 - 20.0) / 17.0, kz = (20.0 - 17.0) / 15.0;
  std::mt19937_64 rng(7);
  for (int n = 0; n < 100; ++n) {
    const State x = random_state(rng);
    const Vec3 f = sc.f(x);
    EXPECT_NEAR(f[0], kx * x[4] * x[5], 1e-14);
    EXPECT_NEAR(f[1], ky * x[3] * x[5], 1e-14);
    EXPECT_NEAR(f[2], kz * x[3] * x[4], 1e-14);
  }
}

TEST(Spacecraft, MatchesAppendixBWithOrbitalTerms) {
  // A large ω0 so that the orbital terms are not negligible against the gyroscopic ones.
  SpacecraftParams p;
  p.inertia = {12.0, 9.0, 7.0};
  p.orbital_rate = 0.7;
  const Spacecraft sc(p);
  std::mt19937_64 rng(11);
  for (int n = 0; n < 100; ++n) {
    const State x = random_state(rng);
    const Vec3 expected = paper_f(x, 12.0, 9.0, 7.0, 0.7);
    const Vec3 f = sc.f(x);
    for (int i = 0; i < 3; ++i) EXPECT_NEAR(f[i], expected[i], 1e-12) << "axis " << i + 1;
  }
}

TEST(Spacecraft, PseudoInverseIsRightInverse) {
  const Spacecraft sc;
  const Mat34 G = sc.G(State::Zero());
  EXPECT_EQ(G, Spacecraft::distribution_matrix());
  const Eigen::Matrix3d I = G * sc.G_pinv(State::Zero());
  EXPECT_TRUE(I.isApprox(Eigen::Matrix3d::Identity(), 1e-14)) << I;
  EXPECT_NEAR(G(1, 1), -0.69, 0.0);
  EXPECT_NEAR(G(2, 3), -0.28, 0.0);
}

TEST(Spacecraft, RejectsNonPositiveInertia) {
  SpacecraftParams p;
  p.inertia = {20.0, 0.0, 15.0};
  try {
    Spacecraft sc(p);
    FAIL() << "expected InputError";
  } catch (const ftc::InputError& e) {
    ASSERT_EQ(e.errors().size(), 1u);
    EXPECT_EQ(e.errors()[0].path, "/inertia/1");
  }
}

TEST(Spacecraft, WorkspaceEvaluationAgreesWithDirectOne) {
  SpacecraftParams p;
  p.orbital_rate = 0.3;
  const Spacecraft sc(p);
  Spacecraft::Workspace ws;
  State x;
  x << 0.4, -0.2, 1.1, 0.5, -0.3, 0.8;
  for (int k = 0; k < 5000; ++k) {
    x.head<3>() += 1e-3 * x.tail<3>();
    const Vec3 a = sc.f(x, ws), b = sc.f(x);
    for (int i = 0; i < 3; ++i) ASSERT_NEAR(a[i], b[i], 1e-15) << "step " << k;
  }
}
