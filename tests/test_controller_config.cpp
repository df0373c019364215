#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "ftc/sim/controller_config.hpp"

using namespace ftc::sim;

TEST(ControllerConfig, Alpha1DerivesFromAlpha2) {
  ControllerConfig c;
  EXPECT_DOUBLE_EQ(c.resolved_alpha1(), 9.0 / 23.0);
  c.alpha1 = 0.3;
  EXPECT_EQ(c.resolved_alpha1(), 0.3);
}

// Found by fuzz_job: α2 = 5e-324 is in (0, 1), but the α1 derived from it rounds to 0, so a job
// was accepted whose canonical JSON (and gains file) held α1 = 0, which the loaders refuse.
TEST(ControllerConfig, DerivedAlpha1OutsideItsRangeIsAnError) {
  ControllerConfig c = ControllerConfig::table1(ControllerType::fosmc);
  c.alpha2 = 5e-324;
  ASSERT_EQ(c.resolved_alpha1(), 0.0);
  const std::vector<ftc::FieldError> errs = c.validate("/controller");
  ASSERT_EQ(errs.size(), 1u);
  EXPECT_EQ(errs[0].path, "/controller/alpha1");
  EXPECT_NE(errs[0].message.find("is absent, and its default"), std::string::npos)
      << errs[0].message;
  c.alpha1 = 0.5;  // given, it is used as it is
  EXPECT_TRUE(c.validate("/controller").empty());
  // A bad α2 is reported once, at α2.
  c = ControllerConfig::table1(ControllerType::fosmc);
  c.alpha2 = 1.5;
  ASSERT_EQ(c.validate("/controller").size(), 1u);
  EXPECT_EQ(c.validate("/controller")[0].path, "/controller/alpha2");
  // The smallest α2 whose derived α1 is not 0 is accepted.
  c.alpha2 = 1e-323;
  EXPECT_GT(c.resolved_alpha1(), 0.0);
  EXPECT_TRUE(c.validate("/controller").empty());
}
