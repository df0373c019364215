// sin and cos of large arguments: Payne–Hanek reduction in integer arithmetic.
#include "lanes/elementary.hpp"

#include <bit>
#include <cstdint>

#include "ftc/sim/elementary.hpp"

namespace ftc::sim::lane {
namespace {

// The bits of 2/π after the binary point, 64 to a word, most significant first (computed with
// Machin's formula in exact integer arithmetic). A double's exponent reaches 2^1023, so the
// reduction reads up to bit 970 + 192; 20 words cover 1 280.
constexpr std::uint64_t kTwoOverPiBits[20] = {
    0xA2F9836E4E441529ULL, 0xFC2757D1F534DDC0ULL, 0xDB6295993C439041ULL, 0xFE5163ABDEBBC561ULL,
    0xB7246E3A424DD2E0ULL, 0x06492EEA09D1921CULL, 0xFE1DEB1CB129A73EULL, 0xE88235F52EBB4484ULL,
    0xE99C7026B45F7E41ULL, 0x3991D639835339F4ULL, 0x9C845F8BBDF9283BULL, 0x1FF897FFDE05980FULL,
    0xEF2F118B5A0A6D1FULL, 0x6D367ECF27CB09B7ULL, 0x4F463F669E5FEA2DULL, 0x7527BAC7EBE5F17BULL,
    0x3D0739F78A5292EAULL, 0x6BFB5FB11F8D5D08ULL, 0x56033046FC7B6BABULL, 0xF0CFBC209AF4361DULL};

// Bits j .. j + 63 of 2/π after the binary point (bit 1 is the first), zero before it.
std::uint64_t bits_at(int j) {
  std::uint64_t out = 0;
  for (int b = 0; b < 64; ++b) {
    const int pos = j + b - 1;  // 0-based position after the point
    std::uint64_t bit = 0;
    if (pos >= 0 && pos < 64 * 20) bit = (kTwoOverPiBits[pos / 64] >> (63 - pos % 64)) & 1;
    out = (out << 1) | bit;
  }
  return out;
}

__extension__ typedef unsigned __int128 u128;  // GCC and Clang, on x86-64 and aarch64

}  // namespace

void sincos_large(double x, double& s, double& c) {
  const std::uint64_t bits = std::bit_cast<std::uint64_t>(x);
  const int biased = static_cast<int>(bits >> 52 & 0x7ff);
  if (biased == 0x7ff) {  // ±inf, NaN
    s = c = x - x;
    return;
  }
  // |x| = m · 2^e with m a 53-bit integer (|x| ≥ 2^19 here, so x is normal).
  const std::uint64_t m = (bits & 0x000FFFFFFFFFFFFFULL) | (1ULL << 52);
  const int e = biased - 1075;
  // x·2/π mod 4 from the 192 bits of 2/π that matter: bits up to e - 2 give multiples of 4
  // (dropped), those past e - 1 + 191 fall below the 137 fraction bits kept.
  const int j0 = e - 1;
  const std::uint64_t w0 = bits_at(j0), w1 = bits_at(j0 + 64), w2 = bits_at(j0 + 128);
  // R = m · (w0 w1 w2) as 256 bits r0 r1 r2 r3 (r0 the top word), worth R·2^-190: bits 190 and
  // 191 are the quadrant, bits 0 .. 189 the fraction, and r0 only multiples of 4.
  const u128 p2 = static_cast<u128>(m) * w2;
  const u128 p1 = static_cast<u128>(m) * w1;
  const u128 p0 = static_cast<u128>(m) * w0;
  const std::uint64_t r3 = static_cast<std::uint64_t>(p2);
  const u128 t2 = (p2 >> 64) + static_cast<std::uint64_t>(p1);
  const std::uint64_t r2 = static_cast<std::uint64_t>(t2);
  const u128 t1 = (t2 >> 64) + (p1 >> 64) + static_cast<std::uint64_t>(p0);
  const std::uint64_t r1 = static_cast<std::uint64_t>(t1);
  int quadrant = static_cast<int>(r1 >> 62);
  // The fraction as f1·2^-64 + f2·2^-128 + f3·2^-192.
  std::uint64_t f1 = (r1 << 2) | (r2 >> 62), f2 = (r2 << 2) | (r3 >> 62), f3 = r3 << 2;
  bool negative = false;
  if (f1 >> 63) {  // fraction ≥ 1/2: take it as fraction - 1, in the next quadrant
    ++quadrant;
    negative = true;
    // 2^192 - (f1 f2 f3): the magnitude of the negative fraction.
    f1 = ~f1;
    f2 = ~f2;
    f3 = ~f3;
    if (++f3 == 0 && ++f2 == 0) ++f1;
  }
  // Normalise so that f1's top bit is set; the fraction is then (f1 + f2·2^-64)·2^(-64-shift).
  int shift = 0;
  if (f1 == 0) {
    f1 = f2;
    f2 = f3;
    f3 = 0;
    shift += 64;
  }
  if (f1 == 0) {  // a fraction below 2^-128 does not occur for a double (worst case ≈ 2^-62)
    s = 0.0;
    c = 1.0;
  } else {
    const int lz = std::countl_zero(f1);
    if (lz > 0) {
      f1 = (f1 << lz) | (f2 >> (64 - lz));
      f2 = (f2 << lz) | (f3 >> (64 - lz));
    }
    shift += lz;
    // f1 + f2·2^-64 as hi + lo: hi the top 53 bits of f1, exact.
    const double hi = static_cast<double>(f1 & ~0x7FFULL);
    const double lo = static_cast<double>(f1 & 0x7FFULL) + static_cast<double>(f2 >> 11) * 0x1p-53;
    // y = (hi + lo)·π/2 · 2^(-64-shift), in double-double.
    constexpr double kPio2Hi = 0x1.921fb54442d18p+0, kPio2Lo = 0x1.1a62633145c07p-54;
    double ph, pl;
    detail::two_prod(hi, kPio2Hi, ph, pl);
    pl += hi * kPio2Lo + lo * kPio2Hi;
    const double scale = std::bit_cast<double>(static_cast<std::uint64_t>(1023 - 64 - shift) << 52);
    double y0 = (ph + pl);
    double y1 = pl - (y0 - ph);
    y0 *= scale;
    y1 *= scale;
    if (negative) {
      y0 = -y0;
      y1 = -y1;
    }
    double ks, kc;
    detail::sincos_kernel(y0, y1, ks, kc);
    switch (quadrant & 3) {
      case 0:
        s = ks;
        c = kc;
        break;
      case 1:
        s = kc;
        c = -ks;
        break;
      case 2:
        s = -ks;
        c = -kc;
        break;
      default:
        s = -kc;
        c = ks;
        break;
    }
  }
  if (x < 0) s = -s;
}

}  // namespace ftc::sim::lane

namespace ftc::sim::math {

double sin(double x) {
  double s, c;
  lane::sincos<double>(x, s, c);
  return s;
}
double cos(double x) {
  double s, c;
  lane::sincos<double>(x, s, c);
  return c;
}
void sincos(double x, double& s, double& c) { lane::sincos<double>(x, s, c); }
double exp(double x) { return lane::exp<double>(x); }
double expm1(double x) { return lane::expm1<double>(x); }
double tanh(double x) { return lane::tanh<double>(x); }
double log(double x) { return lane::log<double>(x); }

}  // namespace ftc::sim::math
