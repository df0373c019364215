// The element-wise helpers of sliding-mode control (sim_core/controllers/laws.hpp).
#include <gtest/gtest.h>

#include <cmath>

#include "controllers/laws.hpp"

using namespace ftc::sim;

TEST(Sliding, SigAndSigmoid) {
  EXPECT_EQ(sig(0.0, 0.5), 0.0);
  EXPECT_DOUBLE_EQ(sig(-4.0, 0.5), -2.0);
  EXPECT_DOUBLE_EQ(sig(9.0, 0.5), 3.0);
  // sigm(s) = tanh(θ s / 2) = (e^{θs} - 1)/(e^{θs} + 1), without overflow at large θ s.
  const double theta = 1000.0;
  EXPECT_DOUBLE_EQ(law::sigm_of(0.5 * theta * 0.001), (std::exp(1.0) - 1) / (std::exp(1.0) + 1));
  EXPECT_DOUBLE_EQ(law::sigm_of(0.5 * theta * -0.002), -(std::exp(2.0) - 1) / (std::exp(2.0) + 1));
  EXPECT_EQ(law::sigm_of(0.5 * theta * 10.0), 1.0);
}

// Beyond |y| = 19.5 the scalar sigm returns the sign without calling tanh; it must be the bits
// tanh gives (the SIMD lanes always call it).
TEST(Sliding, SigmoidShortcutIsExact) {
  for (double y = 18.0; y < 40.0; y += 1.0 / 64)
    for (const double v : {y, -y}) {
      EXPECT_EQ(law::sigm_of(v), std::tanh(v)) << v;
      EXPECT_EQ(law::sigm_of(v), lane::tanh(v)) << v;
    }
}
