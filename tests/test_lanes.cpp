// The elementary functions give the same bits in every SIMD lane, for SSE2, AVX2 and AVX-512,
// as the scalar code: what makes a tuning result independent of the instruction set. The
// arguments cover the simulation's ranges and the special values (zeros, subnormals, huge,
// infinite, NaN), with neighbouring lanes deliberately unlike each other so that a lane taking
// another's path (the large-argument sin/cos, exp's clamps) would show.
#include <gtest/gtest.h>

#include <bit>
#include <cstdint>
#include <limits>
#include <random>
#include <vector>

#include "lanes/lane_functions.hpp"

namespace {

std::vector<double> arguments() {
  std::vector<double> xs = {0.0,
                            -0.0,
                            1e-310,
                            -1e-310,
                            1e-300,
                            1.0,
                            -1.0,
                            0.5,
                            19.4,
                            19.6,
                            -19.6,
                            700.0,
                            709.9,
                            -745.0,
                            -750.0,
                            1e6,
                            -3e8,
                            1e300,
                            std::numeric_limits<double>::infinity(),
                            -std::numeric_limits<double>::infinity(),
                            std::numeric_limits<double>::quiet_NaN(),
                            2.0,
                            1.5707963267948966,
                            3.0};
  std::mt19937_64 g(7);
  std::uniform_real_distribution<double> small(-20, 20), wide(-800, 800), huge(0, 300);
  for (int i = 0; i < 30000; ++i) {
    xs.push_back(small(g));
    xs.push_back(wide(g));
    xs.push_back((i % 2 ? -1 : 1) * std::pow(10.0, huge(g) - 150));
  }
  while (xs.size() % 8) xs.push_back(0.25);
  return xs;
}

using LaneFn = void (*)(const double*, std::size_t, double*);

void expect_same_bits_as_scalar(LaneFn lanes) {
  const std::vector<double> xs = arguments();
  const std::size_t n = xs.size();
  std::vector<double> want(ftc::test::kLaneFunctions * n), got(want.size());
  ftc::test::lanes_scalar(xs.data(), n, want.data());
  lanes(xs.data(), n, got.data());
  const char* names[] = {"sin", "cos", "exp", "expm1", "tanh", "log", "sig"};
  for (int f = 0; f < ftc::test::kLaneFunctions; ++f) {
    int mismatches = 0;
    for (std::size_t i = 0; i < n; ++i) {
      const std::size_t k = f * n + i;
      if (std::bit_cast<std::uint64_t>(want[k]) != std::bit_cast<std::uint64_t>(got[k]) &&
          !(want[k] != want[k] && got[k] != got[k]) && mismatches++ < 3)
        ADD_FAILURE() << names[f] << "(" << xs[i] << "): scalar " << want[k] << ", lane " << got[k];
    }
    EXPECT_EQ(mismatches, 0) << names[f];
  }
}

}  // namespace

TEST(Lanes, Sse2GivesTheScalarBits) { expect_same_bits_as_scalar(ftc::test::lanes_sse2); }

TEST(Lanes, Avx2GivesTheScalarBits) {
  if (!__builtin_cpu_supports("avx2")) GTEST_SKIP() << "this CPU has no AVX2";
  expect_same_bits_as_scalar(ftc::test::lanes_avx2);
}

TEST(Lanes, Avx512GivesTheScalarBits) {
  if (!__builtin_cpu_supports("avx512f")) GTEST_SKIP() << "this CPU has no AVX-512F";
  expect_same_bits_as_scalar(ftc::test::lanes_avx512);
}
