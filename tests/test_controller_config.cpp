#include <gtest/gtest.h>

#include <cmath>

#include "ftc/sim/controller_config.hpp"

using namespace ftc::sim;

TEST(ControllerConfig, Alpha1DerivesFromAlpha2) {
  ControllerConfig c;
  EXPECT_DOUBLE_EQ(c.resolved_alpha1(), 9.0 / 23.0);
  c.alpha1 = 0.3;
  EXPECT_EQ(c.resolved_alpha1(), 0.3);
}
