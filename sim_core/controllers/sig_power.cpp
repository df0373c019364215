#include "controllers/sig_power.hpp"

#include <array>
#include <bit>
#include <cmath>
#include <cstdint>

namespace ftc::sim {

// The tables are computed in double-double arithmetic (a value is hi + lo, about 106 bits) from
// IEEE additions, multiplications and divisions only, and rounded to double once at the end.
// libm's exp2l and powl in long double would be simpler, but long double has a 64-bit
// significand on x86-64 and 113 bits on aarch64, and rounding the 64-bit result to double
// rounds twice, which misses the nearest double when the value lies within a 2^-11 ulp of a
// midpoint. That happened to 2^(-37 · 9/23) and made Table 1's adaptive job tune differently
// on the two CPUs. Here every CPU computes the same bits, and each entry is the double nearest
// its value unless that value lies within about 2^-40 ulp of a midpoint.
namespace {

struct DD {
  double hi, lo;
};

// a + b and a · b exactly, as hi + lo: the simulation's own (lanes/elementary.hpp; Veltkamp's
// split, no FMA).
DD two_sum(double a, double b) {
  DD r;
  lane::detail::two_sum(a, b, r.hi, r.lo);
  return r;
}

DD two_prod(double a, double b) {
  DD r;
  lane::detail::two_prod(a, b, r.hi, r.lo);
  return r;
}

// a + b exactly when |a| >= |b| (Dekker).
DD quick_two_sum(double a, double b) {
  const double s = a + b;
  return {s, b - (s - a)};
}

DD add(DD x, DD y) {
  const DD s = two_sum(x.hi, y.hi);
  const DD t = two_sum(x.lo, y.lo);
  const DD r = quick_two_sum(s.hi, s.lo + t.hi);
  return quick_two_sum(r.hi, r.lo + t.lo);
}

DD mul(DD x, DD y) {
  const DD p = two_prod(x.hi, y.hi);
  return quick_two_sum(p.hi, p.lo + (x.hi * y.lo + x.lo * y.hi));
}

DD mul(DD x, double y) {
  const DD p = two_prod(x.hi, y);
  return quick_two_sum(p.hi, p.lo + x.lo * y);
}

DD div(DD x, DD y) {
  const double q1 = x.hi / y.hi;
  DD r = add(x, mul(y, -q1));
  const double q2 = r.hi / y.hi;
  r = add(r, mul(y, -q2));
  const double q3 = r.hi / y.hi;
  return add(quick_two_sum(q1, q2), DD{q3, 0.0});
}

// x · 2^k for an integer k, exactly unless the result is subnormal or overflows.
double times_power_of_two(double x, int k) {
  // Two steps keep each factor a normal double for |k| up to 2044.
  const int k1 = k / 2, k2 = k - k1;
  const auto power = [](int e) {
    return std::bit_cast<double>(static_cast<std::uint64_t>(e + 1023) << 52);
  };
  return x * power(k1) * power(k2);
}

// ln 2 to 107 bits.
constexpr DD kLn2{0x1.62e42fefa39efp-1, 0x1.abc9e3b39803fp-56};

// e^s for |s| <= 0.0055 from its Taylor series to s^11 (the next term is below 2^-110), in
// Horner form with 1/k! as double-doubles.
DD exp_small(DD s) {
  static const std::array<DD, 12> inv_factorial = [] {
    std::array<DD, 12> f{};
    f[0] = {1.0, 0.0};
    for (int k = 1; k < 12; ++k) f[k] = div(f[k - 1], DD{static_cast<double>(k), 0.0});
    return f;
  }();
  DD sum = inv_factorial[11];
  for (int k = 10; k >= 0; --k) sum = add(mul(sum, s), inv_factorial[k]);
  return sum;
}

// 2^p for p = m/64 + g with m an integer and |g| <= 1/128: 2^(m/64) from exp's table of 2^(j/64)
// as double-doubles (lanes/elementary.hpp, within 2^-107) and a power of two, 2^g = e^(g ln 2)
// from exp_small.
double exp2_dd(DD p) {
  const double m = std::nearbyint(p.hi * 64.0);
  if (std::isnan(m)) return m;  // a NaN exponent (or ∞ · 0): a NaN entry, not a bad cast
  if (m > 64.0 * 2000.0) return INFINITY;
  if (m < -64.0 * 2000.0) return 0.0;
  const DD g = two_sum(p.hi - m * 0x1p-6, p.lo);  // the subtraction is exact (Sterbenz)
  const int mi = static_cast<int>(m);
  const int j = ((mi % 64) + 64) % 64;
  const int n = (mi - j) / 64;
  const DD y =
      mul(DD{lane::detail::kExp2Hi[j], lane::detail::kExp2Lo[j]}, exp_small(mul(kLn2, g.hi)));
  // g.lo is below 2^-53 |p|; its share, g.lo ln 2 · 2^g, enters to first order.
  const DD z = add(y, mul(y, kLn2.hi * g.lo));
  return times_power_of_two(z.hi + z.lo, n);
}

// log2(v) for v in [1/2, 1]: 2 atanh(t) / ln 2 with t = (v - 1) / (v + 1), |t| <= 1/3, whose
// odd series reaches 2^-110 within 36 terms.
DD log2_dd(double v) {
  const DD t = div(DD{v - 1.0, 0.0}, two_sum(v, 1.0));  // v - 1 is exact (Sterbenz)
  const DD t2 = mul(t, t);
  DD power = t, sum = t;
  for (int k = 3; k <= 73; k += 2) {
    power = mul(power, t2);
    sum = add(sum, div(power, DD{static_cast<double>(k), 0.0}));
  }
  return div(mul(sum, 2.0), kLn2);
}

}  // namespace

SigPowerTables::SigPowerTables(double exponent) : a(exponent) {
  // C(a, k) = C(a, k - 1) · (a - k + 1) / k.
  DD c{1.0, 0.0};
  for (int k = 0; k < static_cast<int>(b.size()); ++k) {
    b[k] = c.hi + c.lo;
    c = div(mul(c, two_sum(a, -static_cast<double>(k))), DD{static_cast<double>(k + 1), 0.0});
  }
  // 2^(a e): a · e is exact as a double-double.
  for (int i = 0; i < kExponents; ++i)
    scale[i] = exp2_dd(two_prod(a, static_cast<double>(i + kMinBiasedExponent - 1023)));
  // (1 / inv)^a = 2^(-a log2(inv)). The logarithms do not depend on a: computed once.
  static const std::array<DD, kIntervals> log2_inv = [] {
    std::array<DD, kIntervals> l{};
    for (int j = 0; j < kIntervals; ++j) {
      const double centre = 1.0 + (j + 0.5) / kIntervals;  // exact
      l[j] = log2_dd(1.0 / centre);
    }
    return l;
  }();
  for (int j = 0; j < kIntervals; ++j) {
    const double centre = 1.0 + (j + 0.5) / kIntervals;
    inv_centre[j] = 1.0 / centre;
    centre_power[j] = exp2_dd(mul(log2_inv[j], -a));
  }
}

}  // namespace ftc::sim
