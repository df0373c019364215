#pragma once
// The elementary functions of the hot loop, of our own, written once over the lane type T
// (lane.hpp) in IEEE operations only, so that a result is the same to the last bit in a SIMD
// lane, in the scalar runtime, and on any CPU, whatever its libm. Accuracy on the ranges the
// simulation uses, against long double references (tests/test_elementary.cpp): within about one
// ulp for each.
//
//   sincos(x)  x = n·π/2 + y reduced with π/2 in four parts (Cody–Waite, exact for |x| < 2^19·π/2),
//              larger |x| by Payne–Hanek with 1 280 bits of 2/π (elementary.cpp); sin y and cos y
//              by their Taylor series to y^17 and y^16 (|y| ≤ π/4, remainder < 1e-18)
//   exp(x)     x = (64 m + j) ln2/64 + r, |r| ≤ ln2/128: 2^m by bits, 2^(j/64) from a table,
//              e^r by its Taylor series to r^7
//   expm1(x)   the same reduction, 2^k (1 + p) − 1 formed so that nothing cancels
//   tanh(x)    from expm1(∓2|x|) (below and above |x| = 1), with the sign of x; ±1 past
//              |x| = 19.5, where tanh is ±1 in double precision
//   log(x)     x = 2^e m, m in [√2/2, √2), log m = 2 atanh(f / (2 + f)), f = m − 1, by its series
//
// Polynomial coefficients are the Taylor ones (1/k!, 2/(2k+1)), rounded to double; the series
// run long enough that the truncation is far below an ulp, so no minimax fit is needed and every
// constant can be checked by hand.
#include <cstdint>

#include "lanes/lane.hpp"

namespace ftc::sim::lane {

// Scalar sin and cos of |x| ≥ 2^19·π/2, infinities and NaN: elementary.cpp (compiled once, for
// the baseline instruction set, so outside the per-instruction-set namespace).
void sincos_large(double x, double& s, double& c);

inline namespace FTC_ISA_NS {

namespace detail {

// π/2 = kPio2_1 + kPio2_2 + kPio2_3 + kPio2_3t; the first three have 33 significant bits, so
// n times each of them is exact for |n| < 2^20.
inline constexpr double kPio2_1 = 0x1.921fb544p+0;
inline constexpr double kPio2_2 = 0x1.0b4611a6p-34;
inline constexpr double kPio2_3 = 0x1.3198a2ep-69;
inline constexpr double kPio2_3t = 0x1.b839a252049c1p-104;
inline constexpr double kTwoOverPi = 0x1.45f306dc9c883p-1;
inline constexpr double kReduceLimit = 823549.6;  // < 2^19·π/2: |n| ≤ 2^19
// ln 2 = kLn2Hi + kLn2Lo, kLn2Hi with 32 significant bits (k·kLn2Hi exact for |k| < 2^21).
inline constexpr double kLn2Hi = 0x1.62e42feep-1;
inline constexpr double kLn2Lo = 0x1.a39ef35793c76p-33;
inline constexpr double kInvLn2 = 0x1.71547652b82fep+0;
// ln2/64 = kLn2By64Hi + kLn2By64Lo (36 significant bits in the first), and 64/ln2.
inline constexpr double kLn2By64Hi = 0x1.62e42fefa0000p-7;
inline constexpr double kLn2By64Lo = 0x1.cf79abc9e3b3ap-46;
inline constexpr double k64ByLn2 = 0x1.71547652b82fep+6;
// 2^(j/64) = kExp2Hi[j] + kExp2Lo[j], j = 0 .. 63 (computed in 60-digit decimal arithmetic).
inline constexpr double kExp2Hi[64] = {
    0x1.0000000000000p+0, 0x1.02c9a3e778061p+0, 0x1.059b0d3158574p+0, 0x1.0874518759bc8p+0,
    0x1.0b5586cf9890fp+0, 0x1.0e3ec32d3d1a2p+0, 0x1.11301d0125b51p+0, 0x1.1429aaea92de0p+0,
    0x1.172b83c7d517bp+0, 0x1.1a35beb6fcb75p+0, 0x1.1d4873168b9aap+0, 0x1.2063b88628cd6p+0,
    0x1.2387a6e756238p+0, 0x1.26b4565e27cddp+0, 0x1.29e9df51fdee1p+0, 0x1.2d285a6e4030bp+0,
    0x1.306fe0a31b715p+0, 0x1.33c08b26416ffp+0, 0x1.371a7373aa9cbp+0, 0x1.3a7db34e59ff7p+0,
    0x1.3dea64c123422p+0, 0x1.4160a21f72e2ap+0, 0x1.44e086061892dp+0, 0x1.486a2b5c13cd0p+0,
    0x1.4bfdad5362a27p+0, 0x1.4f9b2769d2ca7p+0, 0x1.5342b569d4f82p+0, 0x1.56f4736b527dap+0,
    0x1.5ab07dd485429p+0, 0x1.5e76f15ad2148p+0, 0x1.6247eb03a5585p+0, 0x1.6623882552225p+0,
    0x1.6a09e667f3bcdp+0, 0x1.6dfb23c651a2fp+0, 0x1.71f75e8ec5f74p+0, 0x1.75feb564267c9p+0,
    0x1.7a11473eb0187p+0, 0x1.7e2f336cf4e62p+0, 0x1.82589994cce13p+0, 0x1.868d99b4492edp+0,
    0x1.8ace5422aa0dbp+0, 0x1.8f1ae99157736p+0, 0x1.93737b0cdc5e5p+0, 0x1.97d829fde4e50p+0,
    0x1.9c49182a3f090p+0, 0x1.a0c667b5de565p+0, 0x1.a5503b23e255dp+0, 0x1.a9e6b5579fdbfp+0,
    0x1.ae89f995ad3adp+0, 0x1.b33a2b84f15fbp+0, 0x1.b7f76f2fb5e47p+0, 0x1.bcc1e904bc1d2p+0,
    0x1.c199bdd85529cp+0, 0x1.c67f12e57d14bp+0, 0x1.cb720dcef9069p+0, 0x1.d072d4a07897cp+0,
    0x1.d5818dcfba487p+0, 0x1.da9e603db3285p+0, 0x1.dfc97337b9b5fp+0, 0x1.e502ee78b3ff6p+0,
    0x1.ea4afa2a490dap+0, 0x1.efa1bee615a27p+0, 0x1.f50765b6e4540p+0, 0x1.fa7c1819e90d8p+0};
inline constexpr double kExp2Lo[64] = {0x0.0p+0,
                                       -0x1.19083535b085dp-56,
                                       0x1.d73e2a475b465p-55,
                                       0x1.186be4bb284ffp-57,
                                       0x1.8a62e4adc610bp-54,
                                       0x1.03a1727c57b53p-59,
                                       -0x1.6c51039449b3ap-54,
                                       -0x1.32fbf9af1369ep-54,
                                       -0x1.19041b9d78a76p-55,
                                       0x1.e5b4c7b4968e4p-55,
                                       0x1.e016e00a2643cp-54,
                                       0x1.dc775814a8495p-55,
                                       0x1.9b07eb6c70573p-54,
                                       0x1.2bd339940e9d9p-55,
                                       0x1.612e8afad1255p-55,
                                       0x1.0024754db41d5p-54,
                                       0x1.6f46ad23182e4p-55,
                                       0x1.32721843659a6p-54,
                                       -0x1.63aeabf42eae2p-54,
                                       -0x1.5e436d661f5e3p-56,
                                       0x1.ada0911f09ebcp-55,
                                       -0x1.ef3691c309278p-58,
                                       0x1.89b7a04ef80d0p-59,
                                       0x1.3c1a3b69062f0p-56,
                                       0x1.d4397afec42e2p-56,
                                       -0x1.4b309d25957e3p-54,
                                       -0x1.07abe1db13cadp-55,
                                       0x1.9bb2c011d93adp-54,
                                       0x1.6324c054647adp-54,
                                       0x1.ba6f93080e65ep-54,
                                       -0x1.383c17e40b497p-54,
                                       -0x1.bb60987591c34p-54,
                                       -0x1.bdd3413b26456p-54,
                                       -0x1.bbe3a683c88abp-57,
                                       -0x1.16e4786887a99p-55,
                                       -0x1.0245957316dd3p-54,
                                       -0x1.41577ee04992fp-55,
                                       0x1.05d02ba15797ep-56,
                                       -0x1.d4c1dd41532d8p-54,
                                       -0x1.fc6f89bd4f6bap-54,
                                       0x1.6e9f156864b27p-54,
                                       0x1.5cc13a2e3976cp-55,
                                       -0x1.75fc781b57ebcp-57,
                                       -0x1.d185b7c1b85d1p-54,
                                       0x1.c7c46b071f2bep-56,
                                       -0x1.359495d1cd533p-54,
                                       -0x1.d2f6edb8d41e1p-54,
                                       0x1.0fac90ef7fd31p-54,
                                       0x1.7a1cd345dcc81p-54,
                                       -0x1.2805e3084d708p-57,
                                       -0x1.5584f7e54ac3bp-56,
                                       0x1.23dd07a2d9e84p-55,
                                       0x1.11065895048ddp-55,
                                       0x1.2884dff483cadp-54,
                                       0x1.503cbd1e949dbp-56,
                                       -0x1.cbc3743797a9cp-54,
                                       0x1.2ed02d75b3707p-55,
                                       0x1.c2300696db532p-54,
                                       -0x1.1a5cd4f184b5cp-54,
                                       0x1.39e8980a9cc8fp-55,
                                       -0x1.e9c23179c2893p-54,
                                       0x1.dc7f486a4b6b0p-54,
                                       0x1.9d3e12dd8a18bp-54,
                                       0x1.74853f3a5931ep-55};

// s + e = a + b exactly (Knuth's two-sum).
template <class T>
FTC_HOT_INLINE void two_sum(const T& a, const T& b, T& s, T& e) {
  s = a + b;
  const T bb = s - a;
  e = (a - (s - bb)) + (b - bb);
}

// hi + lo = a·b exactly, by Veltkamp's splitting (no FMA).
template <class T>
FTC_HOT_INLINE void two_prod(const T& a, const T& b, T& hi, T& lo) {
  const T split(134217729.0);  // 2^27 + 1
  const T ca = split * a, cb = split * b;
  const T ah = ca - (ca - a), al = a - ah;
  const T bh = cb - (cb - b), bl = b - bh;
  hi = a * b;
  lo = ((ah * bh - hi) + ah * bl + al * bh) + al * bl;
}

// sin(y0 + y1) and cos(y0 + y1) for |y0| ≤ π/4 + 1 ulp, |y1| ≤ ulp(y0).
template <class T>
FTC_HOT_INLINE void sincos_kernel(const T& y0, const T& y1, T& s, T& c) {
  const T z = y0 * y0;
  // P(z) = -1/3! + z/5! - ... + z^7/17! and Q(z) = 1/4! - z/6! + ... + z^6/16!, in Estrin's
  // scheme (independent pairs, a short dependency chain).
  const T z2 = z * z, z4 = z2 * z2;
  const T P = (T(-1.0 / 6) + z * T(1.0 / 120)) + z2 * (T(-1.0 / 5040) + z * T(1.0 / 362880)) +
              z4 * ((T(-1.0 / 39916800) + z * T(1.0 / 6227020800)) +
                    z2 * (T(-1.0 / 1307674368000) + z * T(1.0 / 355687428096000)));
  const T Q =
      (T(1.0 / 24) + z * T(-1.0 / 720)) + z2 * (T(1.0 / 40320) + z * T(-1.0 / 3628800)) +
      z4 * ((T(1.0 / 479001600) + z * T(-1.0 / 87178291200)) + z2 * T(1.0 / 20922789888000));
  const T hz = T(0.5) * z;
  // The tail y1 moves sin by y1·cos y0 ≈ y1 (1 - z/2) and cos by -y1·sin y0 ≈ -y1 y0.
  s = y0 + (y0 * z * P + y1 * (T(1.0) - hz));
  const T w = T(1.0) - hz;
  c = w + (((T(1.0) - w) - hz) + (z * z * Q - y0 * y1));
}

// e^(r + rl) - 1 for |r| ≤ ln2/2 + ε and rl the tail of r: r + (rl + r² (1/2! + r/3! + ... +
// r^11/13!)).
template <class T>
FTC_HOT_INLINE T expm1_kernel(const T& r, const T& rl) {
  // Estrin's scheme: the pairs are independent, which shortens the chain of dependent
  // operations from 24 to about 8 (the leading terms r + rl dominate the rounding either way).
  const T r2 = r * r, r4 = r2 * r2;
  const T a0 = T(1.0 / 2) + r * T(1.0 / 6), a1 = T(1.0 / 24) + r * T(1.0 / 120);
  const T a2 = T(1.0 / 720) + r * T(1.0 / 5040), a3 = T(1.0 / 40320) + r * T(1.0 / 362880);
  const T a4 = T(1.0 / 3628800) + r * T(1.0 / 39916800);
  const T a5 = T(1.0 / 479001600) + r * T(1.0 / 6227020800);
  const T p = (a0 + r2 * a1) + r4 * ((a2 + r2 * a3) + r4 * (a4 + r2 * a5));
  return r + (rl + r * r * p);
}

// x = k ln2 + r + rl: k integral, r + rl = x - k ln2 in double-double.
template <class T>
FTC_HOT_INLINE T reduce_ln2(const T& x, T& k, T& rl) {
  k = lane::round_to_int(x * T(kInvLn2));
  const T a = x - k * T(kLn2Hi);  // exact
  const T b = k * T(kLn2Lo);
  const T r = a - b;
  rl = (a - r) - b;
  return r;
}

}  // namespace detail

// sin x and cos x.
template <class T>
FTC_HOT_INLINE void sincos(const T& x, T& s, T& c) {
  using namespace detail;
  const lane::Mask<T> small = lane::abs(x) <= T(kReduceLimit);  // false for NaN
  const T xs = lane::select(small, x, T(0.0));
  const T n = lane::round_to_int(xs * T(kTwoOverPi));
  // xs - n·π/2 in double-double: the first difference is exact (Sterbenz), the products too.
  const T a = xs - n * T(kPio2_1);
  T s1, e1, s2, e2;
  detail::two_sum(a, -(n * T(kPio2_2)), s1, e1);
  detail::two_sum(s1, -(n * T(kPio2_3)), s2, e2);
  const T tail = (e1 + e2) - n * T(kPio2_3t);
  const T y0 = s2 + tail;
  const T y1 = tail - (y0 - s2);
  T ks, kc;
  sincos_kernel(y0, y1, ks, kc);
  // The quadrant n mod 4, as 0, 1, 2 or 3.
  const T q = n - T(4.0) * lane::floor_int(n * T(0.25));
  const lane::Mask<T> odd = (q == T(1.0)) | (q == T(3.0));
  const T sv = lane::select(odd, kc, ks);
  const T cv = lane::select(odd, ks, kc);
  // sin: +sv in quadrants 0, 1, −sv in 2, 3; cos: +cv in 0, 3, −cv in 1, 2.
  s = lane::select(q >= T(2.0), -sv, sv);
  c = lane::select((q == T(1.0)) | (q == T(2.0)), -cv, cv);
  if (!lane::all(small)) [[unlikely]] {
    for (int i = 0; i < lane::kWidth<T>; ++i)
      if (!lane::mask_lane(small, i)) {
        double si, ci;
        sincos_large(lane::lane_of(x, i), si, ci);
        lane::set_lane(s, i, si);
        lane::set_lane(c, i, ci);
      }
  }
}

namespace detail {
// e^x = 2^m · y for |x| ≤ 746: x = (64 m + j) ln2/64 + r, |r| ≤ ln2/128, y = 2^(j/64) · e^r in
// [1, 2) up to rounding, with 2^(j/64) from the table in double-double and e^r - 1 from its
// Taylor series to r^7 (remainder < 1e-19).
template <class T>
FTC_HOT_INLINE T exp_reduced(const T& x, T& m) {
  const T k = lane::round_to_int(x * T(k64ByLn2));
  const T a = x - k * T(kLn2By64Hi);  // exact: k has at most 17 bits
  const T b = k * T(kLn2By64Lo);
  const T r = a - b;
  const T rl = (a - r) - b;
  m = lane::floor_int(k * T(1.0 / 64));
  // j = k mod 64 in 0 .. 63, read as an integer from the low bits of k + 1.5·2^52 (exact for
  // |k| < 2^51; k < 0 too, as 2^51 is a multiple of 64); a NaN x reads some entry of the table
  // and gives NaN through r.
  const auto j = lane::bits_of(k + T(0x1.8p52)) & 63;
  const T hi = lane::gather_at(kExp2Hi, j), lo = lane::gather_at(kExp2Lo, j);
  const T r2 = r * r;
  const T p =
      r +
      (rl + r2 * ((T(1.0 / 2) + r * T(1.0 / 6)) + r2 * ((T(1.0 / 24) + r * T(1.0 / 120)) +
                                                        r2 * (T(1.0 / 720) + r * T(1.0 / 5040)))));
  return hi + (lo + hi * p);
}
}  // namespace detail

// e^x.
template <class T>
FTC_HOT_INLINE T exp(const T& x) {
  using namespace detail;
  // For |x| < 700 (false for NaN) e^x is a normal number and y · 2^m is exact: one product,
  // the same bits as the two below.
  if (lane::all(lane::abs(x) < T(700.0))) [[likely]] {
    T m;
    const T y = exp_reduced(x, m);
    return y * lane::pow2i(m);
  }
  // Clamped so that k stays in range; e^x overflows past 709.79 and underflows to 0 below
  // -745.14, which the clamped values still do. NaN passes through.
  const T xc = lane::select(x > T(710.0), T(710.0), lane::select(x < T(-746.0), T(-746.0), x));
  T m;
  const T y = exp_reduced(xc, m);
  // 2^m in two factors, so that m down to -1075 and up to 1024 is representable; the first
  // product is exact, the second rounds once (into the subnormals or to infinity at the ends).
  const T h = lane::round_to_int(m * T(0.5));
  return (y * lane::pow2i(h)) * lane::pow2i(m - h);
}

// e^x - 1, for x ≤ 40 (tanh's range; larger x gives e^x - 1 rounded twice).
template <class T>
FTC_HOT_INLINE T expm1(const T& x) {
  const T xc = lane::select(x < T(-60.0), T(-60.0), lane::select(x > T(700.0), T(700.0), x));
  T k, rl;
  const T r = detail::reduce_ln2(xc, k, rl);
  const T p = detail::expm1_kernel(r, rl);
  const T two_k = lane::pow2i(k);
  // 2^k (1 + p) - 1 = (2^k - 1) + 2^k p; 2^k - 1 is exact for -53 ≤ k ≤ 53.
  const T result = (two_k - T(1.0)) + two_k * p;
  // For |x| < ln2/2 (k = 0) this is p itself; keep NaN.
  return lane::select(lane::is_nan(x), x, result);
}

// tanh x.
template <class T>
FTC_HOT_INLINE T tanh(const T& x) {
  const T ax = lane::abs(x);
  // Below 1: -t / (2 + t) with t = e^(-2|x|) - 1 in (-0.87, 0]; from 1 on: 1 - 2 / (t + 2) with
  // t = e^(2|x|) - 1, where the quotient is small and its rounding hardly shows in the result.
  const lane::Mask<T> below1 = ax < T(1.0);
  const T t =
      lane::expm1(lane::select(below1, T(-2.0), T(2.0)) * lane::select(ax > T(19.5), T(19.5), ax));
  // Below 1 the quotient is the result, so its two roundings (of 2 + t and of the division)
  // are taken back by one correction step in double-double.
  const T d = T(2.0) + t;
  const T dl = (T(2.0) - d) + t;  // d + dl = 2 + t exactly
  const T inv = T(1.0) / d;
  const T q = -t * inv;
  T ph, pl;
  detail::two_prod(q, d, ph, pl);
  const T small = q + ((((-t) - ph) - pl) - q * dl) * inv;
  const T v = lane::select(below1, small, T(1.0) - T(2.0) * inv);
  // Past 19.5, 1 - tanh|x| < 2^-54: the value is 1 in double precision.
  return lane::copysign(lane::select(ax > T(19.5), T(1.0), v), x);
}

// ln x (x > 0; 0 gives -inf, x < 0 NaN, +inf +inf).
template <class T>
FTC_HOT_INLINE T log(const T& x) {
  const lane::Mask<T> subnormal = x < T(0x1p-1022);
  const T xs = lane::select(subnormal, x * T(0x1p54), x);
  T e = lane::biased_exponent(xs) - lane::select(subnormal, T(1077.0), T(1023.0));
  T m = lane::significand(xs);
  const lane::Mask<T> high = m > T(1.4142135623730951);
  m = lane::select(high, m * T(0.5), m);
  e = lane::select(high, e + T(1.0), e);
  const T f = m - T(1.0);  // exact
  const T s = f / (T(2.0) + f);
  const T z = s * s;
  // R = 2 s²/3 + 2 s⁴/5 + ...: log(1 + f) = f - f²/2 + s (f²/2 + R).
  const T z2 = z * z, z4 = z2 * z2;
  const T R = z * ((T(2.0 / 3) + z * T(2.0 / 5)) + z2 * (T(2.0 / 7) + z * T(2.0 / 9)) +
                   z4 * ((T(2.0 / 11) + z * T(2.0 / 13)) + z2 * (T(2.0 / 15) + z * T(2.0 / 17)) +
                         z4 * (T(2.0 / 19) + z * T(2.0 / 21))));
  const T hfsq = T(0.5) * f * f;
  const T y = e * T(detail::kLn2Hi) - ((hfsq - (s * (hfsq + R) + e * T(detail::kLn2Lo))) - f);
  // Special values: 0 → -inf, negative → NaN, +inf and NaN themselves.
  T out = lane::select(x == T(0.0), T(-__builtin_inf()), y);
  out = lane::select(x < T(0.0), T(__builtin_nan("")), out);
  return lane::select((x == T(__builtin_inf())) | lane::is_nan(x), x, out);
}

// sig^a(x) = |x|^a sign(x) as e^(a ln|x|); sig^a(0) = 0. The controllers use SigPower (more
// accurate, faster); this is its fallback far from 1 and its reference definition.
template <class T>
FTC_HOT_INLINE T sig(const T& x, const T& a) {
  const T p = lane::exp(a * lane::log(lane::abs(x)));
  return lane::select(x == T(0.0), T(0.0), lane::copysign(p, x));
}

}  // namespace FTC_ISA_NS
}  // namespace ftc::sim::lane
