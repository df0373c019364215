// The element-wise helpers of sliding-mode control (sim_core/controllers/sliding.hpp).
#include <gtest/gtest.h>

#include <cmath>

#include "controllers/sliding.hpp"

using namespace ftc::sim;

TEST(Sliding, SigAndSigmoid) {
  EXPECT_EQ(sig(0.0, 0.5), 0.0);
  EXPECT_DOUBLE_EQ(sig(-4.0, 0.5), -2.0);
  EXPECT_DOUBLE_EQ(sig(9.0, 0.5), 3.0);
  // sigm(s) = (e^{θs} - 1)/(e^{θs} + 1), without overflow at large θ s.
  const Vec3 s = sigm(Vec3(0.001, -0.002, 10.0), 1000.0);
  EXPECT_DOUBLE_EQ(s[0], (std::exp(1.0) - 1) / (std::exp(1.0) + 1));
  EXPECT_DOUBLE_EQ(s[1], -(std::exp(2.0) - 1) / (std::exp(2.0) + 1));
  EXPECT_EQ(s[2], 1.0);
}

// Beyond |y| = 19.5 sigm returns the sign without calling tanh; it must be the same bits.
TEST(Sliding, SigmoidShortcutIsExact) {
  for (double y = 18.0; y < 40.0; y += 1.0 / 64)
    for (const double v : {y, -y}) {
      const Vec3 s = sigm(Vec3(v, 0.0, 0.0), 2.0);  // θ = 2: sigm(s) = tanh(s)
      EXPECT_EQ(s[0], std::tanh(v)) << v;
    }
}
