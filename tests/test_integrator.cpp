#include <gtest/gtest.h>

#include <cmath>
#include <span>
#include <vector>

#include "constant_command.hpp"
#include "ftc/sim/integrator.hpp"
#include "ftc/sim/simulation.hpp"
#include "ftc/sim/spacecraft.hpp"

using namespace ftc::sim;
using namespace ftc::testing;

namespace {

State open_loop_final(int substeps) {
  SpacecraftParams p;
  p.orbital_rate = 0.05;  // make the orbital terms matter too
  const Spacecraft plant(p);
  Scenario s = Scenario::paper();
  s.faults.clear();
  s.duration = 2.0;
  s.sample_time = 0.05;
  s.substeps = substeps;
  s.initial_state = {0.3, -0.2, 0.5, 0.4, -0.6, 0.2};
  ConstantCommand c(Vec4(0.1, -0.2, 0.05, 0.1));
  return state_of(simulate(plant, c, s).final_state);
}

}  // namespace

TEST(Integrator, Rk4StepIsExactForCubic) {
  // dx/dt = 3 t² has x(t) = t³, a polynomial RK4 integrates exactly.
  using V = Eigen::Matrix<double, 1, 1>;
  V x = V::Zero();
  const double h = 0.1;
  for (int k = 0; k < 10; ++k)
    x = rk4_step(x, k * h, h, [](double t, const V&) { return V(3.0 * t * t); });
  EXPECT_NEAR(x[0], 1.0, 1e-14);
}

TEST(Integrator, Rk4ShowsFourthOrderConvergence) {
  const State ref = open_loop_final(256);
  const double e1 = (open_loop_final(1) - ref).norm();
  const double e2 = (open_loop_final(2) - ref).norm();
  const double e4 = (open_loop_final(4) - ref).norm();
  ASSERT_GT(e1, 1e-10);  // the error must be measurable for the ratio to mean anything
  EXPECT_NEAR(e1 / e2, 16.0, 2.0) << "e1=" << e1 << " e2=" << e2;
  EXPECT_NEAR(e2 / e4, 16.0, 2.0) << "e2=" << e2 << " e4=" << e4;
}
