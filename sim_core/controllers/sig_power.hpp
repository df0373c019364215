#pragma once
// sig^a(x) = |x|^a sign(x) for one exponent a fixed at construction, without libm in the hot
// loop.
//
// The full-order surface evaluates six of these every sample, and as exp(a ln|x|) they were
// the largest single cost of a simulation (about a fifth of its cycles). With a fixed, the
// power splits along the floating-point representation |x| = 2^e · m, m in [1, 2):
//
//   |x|^a = 2^(a e) · c^a · (1 + r)^a,   c = the centre of m's 1/128 interval (by its top 7
//                                        mantissa bits),  r = m / c - 1,  |r| <= 1/256
//
// 2^(a e) and c^a come from tables computed once in long double, r from a table of 1/c, and
// (1 + r)^a from its binomial series to r^6 (the next term is below 2e-18). Against the power in
// long double the result is within 5 ulp (mean 0.7 ulp), where exp(a ln|x|) reached 52 ulp
// (mean 7): tests/test_controllers.cpp. Zero, subnormals and |x| outside [2^-64, 2^64), which a
// controller does not meet in practice, take exp(a ln|x|).
#include <array>
#include <bit>
#include <cmath>
#include <cstdint>

#include "ftc/sim/types.hpp"
#include "lanes/elementary.hpp"

namespace ftc::sim {

// sig^a for any exponent, as exp(a ln|x|): SigPower's fallback, and the definition it is
// tested against.
inline double sig(double x, double a) { return lane::sig(x, a); }

class SigPower {
 public:
  explicit SigPower(double a);

  FTC_HOT_INLINE double operator()(double x) const {
    const std::uint64_t bits = std::bit_cast<std::uint64_t>(x);
    const std::uint64_t magnitude = bits & ~kSign;
    const std::uint64_t slot = (magnitude >> 52) - kMinBiasedExponent;  // wraps when below
    if (slot >= kExponents) return fallback(x);
    const Mantissa& t = mantissa_[(magnitude >> 45) & (kIntervals - 1)];
    const double m = std::bit_cast<double>((magnitude & kFraction) | kOne);
    const double r = m * t.inv_centre - 1.0;
    // (1 + r)^a in Estrin form: the terms are independent, which shortens the dependency chain.
    const double r2 = r * r;
    const double p =
        (1.0 + b_[1] * r) + r2 * ((b_[2] + b_[3] * r) + r2 * ((b_[4] + b_[5] * r) + r2 * b_[6]));
    const double y = scale_[slot] * (t.centre_power * p);
    return std::bit_cast<double>(std::bit_cast<std::uint64_t>(y) | (bits & kSign));
  }

 private:
  static constexpr std::uint64_t kSign = 0x8000000000000000ULL;
  static constexpr std::uint64_t kFraction = 0x000FFFFFFFFFFFFFULL;
  static constexpr std::uint64_t kOne = 0x3FF0000000000000ULL;  // the bits of 1.0
  static constexpr int kIntervals = 128;
  static constexpr std::uint64_t kExponents = 128;  // e in [-64, 63]
  static constexpr std::uint64_t kMinBiasedExponent = 1023 - 64;

  struct Mantissa {
    double inv_centre;    // 1/c rounded; r is taken against exactly this value
    double centre_power;  // (1 / inv_centre)^a
  };

  double fallback(double x) const { return sig(x, a_); }

  double a_;
  std::array<double, 7> b_{};               // binomial coefficients C(a, k)
  std::array<double, kExponents> scale_{};  // 2^(a e)
  std::array<Mantissa, kIntervals> mantissa_{};
};

}  // namespace ftc::sim
