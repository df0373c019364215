// The trajectory CSV's number formatting against printf, which it must match character for
// character (the files were printf-written before, and plots and diffs rely on that).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "io/decimal.hpp"

namespace {

std::string g9(double v) {
  char buf[48];
  return std::string(buf, ftc::tune::detail::write_g9(buf, v));
}
std::string f6(double v) {
  char buf[400];  // the room write_f6 needs from 1e15 up
  return std::string(buf, ftc::tune::detail::write_f6(buf, v));
}
std::string printf_g9(double v) {
  char buf[48];
  std::snprintf(buf, sizeof buf, "%.9g", v);
  return buf;
}
std::string printf_f6(double v) {
  char buf[400];
  std::snprintf(buf, sizeof buf, "%.6f", v);
  return buf;
}

}  // namespace

TEST(Decimal, G9MatchesPrintfAtSpecialValues) {
  for (double v : {0.0,
                   -0.0,
                   1.0,
                   -1.0,
                   10.0,
                   100000000.0,
                   999999999.0,
                   1e9,
                   1e-5,
                   1e-4,
                   0.0001234567895,
                   9.9999999949999,
                   9.999999995,
                   9.9999999951,
                   0.5,
                   123456789.5,
                   1234567895.0,
                   1e300,
                   -1e-300,
                   5e-324,
                   std::numeric_limits<double>::max(),
                   std::numeric_limits<double>::infinity(),
                   -std::numeric_limits<double>::infinity(),
                   std::numeric_limits<double>::quiet_NaN()})
    EXPECT_EQ(g9(v), printf_g9(v)) << "value " << printf_g9(v);
}

TEST(Decimal, G9MatchesPrintfOnMillionsOfValues) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> mantissa(-10.0, 10.0);
  std::uniform_int_distribution<int> exponent(-40, 40);
  std::uniform_int_distribution<std::uint64_t> bits;
  int mismatches = 0;
  for (int i = 0; i < 2000000 && mismatches < 10; ++i) {
    double v = mantissa(rng) * std::pow(10.0, exponent(rng));
    if (i % 4 == 1) {  // any bit pattern: subnormals, huge exponents
      const std::uint64_t b = bits(rng);
      std::memcpy(&v, &b, sizeof v);
      if (!std::isfinite(v)) continue;
    } else if (i % 4 == 2) {  // near a nine-digit tie: d.dddddddd5 +- an ulp or two
      const double tie = (std::floor(std::fabs(mantissa(rng)) * 1e8) + 0.5) * 1e-8;
      v = std::nextafter(tie, (i & 8) ? 0.0 : 20.0);
    } else if (i % 4 == 3) {  // short decimals like the states a simulation starts from
      v = std::round(mantissa(rng) * 1000) / 1000;
    }
    if (g9(v) != printf_g9(v)) {
      ++mismatches;
      ADD_FAILURE() << "printf " << printf_g9(v) << " but " << g9(v);
    }
  }
}

TEST(Decimal, F6MatchesPrintfOnSampleTimes) {
  for (int k = 0; k <= 200000; ++k) {
    const double t = k * 0.001;  // how a simulation's clock runs
    ASSERT_EQ(f6(t), printf_f6(t));
    ASSERT_EQ(f6(t + 5e-7), printf_f6(t + 5e-7));  // a tie in decimal, not in binary
  }
  for (double v :
       {-0.0, -1e-9, -0.5, 0.0000005, 1e4, 12345.678, 1e20, -1e300,
        std::numeric_limits<double>::infinity(), std::numeric_limits<double>::quiet_NaN()})
    EXPECT_EQ(f6(v), printf_f6(v)) << "value " << printf_g9(v);
}

// A row at a time, as the trajectory writer prints, gives the same text as number by number,
// for lists of any length (blocks of 16 inside) and with the slow path's values mixed in.
TEST(Decimal, G9ListMatchesOneByOne) {
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> mantissa(-10.0, 10.0);
  std::uniform_int_distribution<int> exponent(-20, 12);
  const double specials[] = {0.0,
                             -0.0,
                             std::numeric_limits<double>::infinity(),
                             std::numeric_limits<double>::quiet_NaN(),
                             1e-300,
                             3e15};
  for (std::size_t count : {0u, 1u, 15u, 16u, 17u, 33u, 100u}) {
    std::vector<double> v(count);
    for (std::size_t i = 0; i < count; ++i)
      v[i] = i % 7 == 3 ? specials[i % 6] : mantissa(rng) * std::pow(10.0, exponent(rng));
    std::string expected;
    for (double x : v) expected += "," + printf_g9(x);
    std::string buf(count * 24 + 8, '\0');
    char* end = ftc::tune::detail::write_g9_list(buf.data(), v.data(), v.size(), ',');
    EXPECT_EQ(std::string(buf.data(), end), expected) << count << " numbers";
  }
}

// The string form the report's gnuplot scripts print numbers with: printf's "%.9g".
TEST(Decimal, G9StringIsPrintfG9) {
  for (double v : {0.0, -0.0, 1.0, -2.5, 0.1, 1e-300, 123456789.5, 3e15, 1.0 / 3.0,
                   std::numeric_limits<double>::infinity(),
                   -std::numeric_limits<double>::infinity(),
                   std::numeric_limits<double>::quiet_NaN()})
    EXPECT_EQ(ftc::tune::detail::g9_string(v), printf_g9(v)) << printf_g9(v);
}
