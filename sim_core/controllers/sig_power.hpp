#pragma once
// sig^a(x) = |x|^a sign(x) for one exponent a fixed at construction, without libm in the hot
// loop, written over the lane type (lanes/lane.hpp) so that the scalar controllers and the SIMD
// simulator evaluate it with the same operations and get the same bits.
//
// The full-order surface evaluates six of these every sample, and as exp(a ln|x|) they were
// the largest single cost of a simulation (about a fifth of its cycles). With a fixed, the
// power splits along the floating-point representation |x| = 2^e · m, m in [1, 2):
//
//   |x|^a = 2^(a e) · c^a · (1 + r)^a,   c = the centre of m's 1/128 interval (by its top 7
//                                        mantissa bits),  r = m / c - 1,  |r| <= 1/256
//
// 2^(a e) and c^a come from tables computed once per exponent in double-double arithmetic (IEEE
// operations only, so the same bits on every CPU; sig_power.cpp), r from a table of 1/c, and
// (1 + r)^a from its binomial series to r^6 (the next term is below 2e-18). Against the power in
// long double the result is within 5 ulp (mean 0.7 ulp), where exp(a ln|x|) reached 52 ulp
// (mean 7): tests/test_sig_power.cpp. Zero, subnormals and |x| outside [2^-64, 2^64), which a
// controller does not meet in practice, take exp(a ln|x|).
//
// In W lanes each lane has its own exponent (candidates may tune α): the lanes' tables lie one
// after another and each lane reads its own with a gather.
#include <array>
#include <bit>
#include <cstddef>
#include <cstdint>

#include "ftc/sim/types.hpp"
#include "lanes/elementary.hpp"

namespace ftc::sim {

// The tables of one exponent (computed in sig_power.cpp, once per controller).
struct SigPowerTables {
  static constexpr int kIntervals = 128;
  static constexpr int kExponents = 128;  // e in [-64, 63]
  static constexpr int kMinBiasedExponent = 1023 - 64;

  explicit SigPowerTables(double a);

  double a;
  std::array<double, 7> b{};                      // binomial coefficients C(a, k)
  std::array<double, kExponents> scale{};         // 2^(a e)
  std::array<double, kIntervals> inv_centre{};    // 1/c rounded; r is taken against it
  std::array<double, kIntervals> centre_power{};  // (1 / inv_centre)^a
};

inline namespace FTC_ISA_NS {

template <class T>
class SigPowerLanes {
 public:
  static constexpr int W = lane::kWidth<T>;
  using Tables = SigPowerTables;

  // One exponent per lane: a[0 .. W).
  explicit SigPowerLanes(const double* a) {
    for (int l = 0; l < W; ++l) {
      a_[l] = a[l];
      base_[l] = l * Tables::kIntervals;
      base_i_[l] = l * Tables::kIntervals;
      // Lanes often share an exponent (α is rarely tuned): the tables (256 powers) once.
      int same = 0;
      while (same < l && a[same] != a[l]) ++same;
      if (same < l) {
        for (int k = 0; k < 7; ++k) b_[k][l] = b_[k][same];
        base_[l] = base_[same];
        base_i_[l] = base_i_[same];
        continue;
      }
      const Tables t(a[l]);
      for (int k = 0; k < 7; ++k) b_[k][l] = t.b[k];
      for (int i = 0; i < Tables::kIntervals; ++i) {
        scale_[l * Tables::kIntervals + i] = t.scale[i];
        inv_centre_[l * Tables::kIntervals + i] = t.inv_centre[i];
        centre_power_[l * Tables::kIntervals + i] = t.centre_power[i];
      }
    }
  }

  FTC_HOT_INLINE T operator()(const T& x) const {
    if constexpr (W == 1) {
      return scalar(x);
    } else {
      return lanes(x);
    }
  }

 private:
  // One lane: the table indices from the bits in integer arithmetic, the rest as in lanes();
  // the same indices and operations, so the same bits, and cheaper than the lanes' way.
  FTC_HOT_INLINE double scalar(double x) const {
    const std::uint64_t bits = std::bit_cast<std::uint64_t>(x);
    const std::uint64_t magnitude = bits & ~(1ULL << 63);
    const std::uint64_t slot = (magnitude >> 52) - Tables::kMinBiasedExponent;  // wraps below
    if (slot >= static_cast<std::uint64_t>(Tables::kExponents)) [[unlikely]]
      return far(x, a_[0]);
    const std::uint64_t i = static_cast<std::uint64_t>(base_[0]) + ((magnitude >> 45) & 127);
    const double m =
        std::bit_cast<double>((magnitude & 0x000FFFFFFFFFFFFFULL) | 0x3FF0000000000000ULL);
    const double r = m * inv_centre_[i] - 1.0;
    const double r2 = r * r;
    const double p = (1.0 + b_[1][0] * r) + r2 * ((b_[2][0] + b_[3][0] * r) +
                                                  r2 * ((b_[4][0] + b_[5][0] * r) + r2 * b_[6][0]));
    return lane::copysign(
        scale_[static_cast<std::size_t>(base_[0]) + slot] * (centre_power_[i] * p), x);
  }

  // W lanes: the same table indices as scalar() from the bits in 64-bit integer lanes (a
  // lane outside the tables reads an arbitrary entry, which the fallback replaces).
  FTC_HOT_INLINE T lanes(const T& x) const {
    using I = decltype(lane::bits_of(x));
    const T mag = lane::abs(x);
    const I bits = lane::bits_of(mag);
    const lane::Mask<T> inside = (mag >= T(0x1p-64)) & (mag < T(0x1p64));  // false for NaN
    const I base = I::load_unaligned(base_i_);
    const I interval = base + ((bits >> 45) & I(Tables::kIntervals - 1));
    const I slot =
        base + (((bits >> 52) - I(Tables::kMinBiasedExponent)) & I(Tables::kExponents - 1));
    const T m = lane::significand(mag);
    const T inv_centre = lane::gather_at(inv_centre_, interval);
    const T centre_power = lane::gather_at(centre_power_, interval);
    const T scale = lane::gather_at(scale_, slot);
    const T r = m * inv_centre - T(1.0);
    // (1 + r)^a in Estrin form: the terms are independent, which shortens the dependency chain.
    const T r2 = r * r;
    const T p =
        (T(1.0) + b(1) * r) + r2 * ((b(2) + b(3) * r) + r2 * ((b(4) + b(5) * r) + r2 * b(6)));
    const T y = lane::copysign(scale * (centre_power * p), x);
    if (lane::all(inside)) [[likely]]
      return y;
    return lane::select(inside, y, far(x, lane::load_lanes<T>(a_)));
  }

  // Zero and far from 1: rare, and out of line so that the six (or twelve) inlined copies of
  // the fast path above stay small (inlined, this path cost PI-FOSMC about 5 % in AVX-512).
  [[gnu::noinline, gnu::cold]] static T far(const T& x, const T& a) { return lane::sig(x, a); }

  FTC_HOT_INLINE T b(int k) const { return lane::load_lanes<T>(b_[k]); }

  double a_[W];
  double base_[W];  // lane l's tables start at l · 128
  std::int64_t base_i_[W];
  double b_[7][W];
  double scale_[W * Tables::kExponents];
  double inv_centre_[W * Tables::kIntervals];
  double centre_power_[W * Tables::kIntervals];
};

}  // namespace FTC_ISA_NS

// The one-lane instance, for the scalar controllers and the tests.
class SigPower : public SigPowerLanes<double> {
 public:
  explicit SigPower(double a) : SigPowerLanes<double>(&a) {}
};

// sig^a for any exponent, as exp(a ln|x|): SigPower's fallback, and the definition it is
// tested against.
inline double sig(double x, double a) { return lane::sig(x, a); }

}  // namespace ftc::sim
