#include "io/decimal.hpp"

#include <algorithm>
#include <bit>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstring>

namespace ftc::tune::detail {

namespace {

// Why this is exact. To print nine significant digits of a = |v| with 10^k <= a < 10^(k+1),
// printf rounds the exact product a·10^s, s = 8 - k, to an integer (ties to even). For
// 0 <= s <= 22 the power 10^s is a double, and Dekker's product splits a·10^s exactly into
// y + e (y the rounded double product, |e| <= ulp(y)/2). Since y < 10^10 < 2^34 (an exponent
// estimated one low included) its ulp is at most 2^-18, so r = round(y) and y - r are exact,
// and the rounding of y + e differs from r's only when y sits on a half-integer, where the sign
// of e (or, for e = 0, evenness) decides. No approximation is
// involved; values outside the fast range (below 1e-14, from 1e9 up, zero, subnormal, inf, NaN)
// take std::to_chars with a precision, which is exact and slower. The file is compiled without
// FMA contraction (the project's flags), which Dekker's product relies on.

struct Split {
  double hi, lo;
};
constexpr Split split(double a) {
  const double c = 134217729.0 * a;  // 2^27 + 1
  const double hi = c - (c - a);
  return {hi, a - hi};
}

constexpr int kMaxPower = 22;  // 10^22 is the largest power of ten that is a double
constexpr double kPow10[kMaxPower + 2] = {1e0,  1e1,  1e2,  1e3,  1e4,  1e5,  1e6,  1e7,
                                          1e8,  1e9,  1e10, 1e11, 1e12, 1e13, 1e14, 1e15,
                                          1e16, 1e17, 1e18, 1e19, 1e20, 1e21, 1e22, 1e23};

struct PowerSplits {
  Split s[kMaxPower + 1];
  constexpr PowerSplits() : s{} {
    for (int i = 0; i <= kMaxPower; ++i) s[i] = split(kPow10[i]);
  }
};
constexpr PowerSplits kSplits;

constexpr char kPairs[] =
    "00010203040506070809101112131415161718192021222324252627282930313233343536373839"
    "40414243444546474849505152535455565758596061626364656667686970717273747576777879"
    "8081828384858687888990919293949596979899";

// Writes the `count` low decimal digits of d, most significant first.
// The eight decimal digits of d < 10^8 as ASCII in one register, the first digit in the lowest
// byte (the order memcpy stores them in on a little-endian machine). Divisions by 100 and by 10
// run in SIMD-within-a-register lanes as multiplications: (x·10486) >> 20 is x/100 for
// x < 10^4 and (x·103) >> 10 is x/10 for x < 100, and no lane's product reaches the next lane.
[[gnu::always_inline]] inline std::uint64_t ascii8(std::uint32_t d) {
  std::uint64_t x = d / 10000u | std::uint64_t{d % 10000u} << 32;  // two 4-digit lanes
  const std::uint64_t hundreds = ((x * 10486u) >> 20) & 0x0000007F0000007Fu;
  x = (x - hundreds * 100u) << 16 | hundreds;  // four 2-digit lanes
  const std::uint64_t tens = ((x * 103u) >> 10) & 0x000F000F000F000Fu;
  x = (x - tens * 10u) << 8 | tens;  // eight digits
  return x | 0x3030303030303030u;
}

// round(a·10^s) for a > 0, 0 <= s <= 22 and a·10^s < 2^51, ties to even, exactly.
[[gnu::always_inline]] inline std::uint64_t scaled_round(double a, int s) {
  const double y = a * kPow10[s];
  const double r = (y + 0x1p52) - 0x1p52;  // y rounded to an integer, ties to even
  const double diff = y - r;               // exact, in [-0.5, 0.5]
  auto d = static_cast<std::uint64_t>(r);
  if (diff == 0.5 || diff == -0.5) [[unlikely]] {
    // Only on a half-integer does the product's rounding error e decide.
    const Split as = split(a), ps = kSplits.s[s];
    const double e = ((as.hi * ps.hi - y) + as.hi * ps.lo + as.lo * ps.hi) + as.lo * ps.lo;
    if (diff == 0.5 && (e > 0 || (e == 0 && (d & 1)))) ++d;
    if (diff == -0.5 && (e < 0 || (e == 0 && (d & 1)))) --d;
  }
  return d;
}

// floor(log10 a) for a normal a > 0 (the estimate from the binary exponent is exact or one low).
int decimal_exponent(double a) {
  std::uint64_t bits = 0;
  std::memcpy(&bits, &a, sizeof bits);
  const int e2 = static_cast<int>((bits >> 52) & 0x7ff) - 1023;  // 2^e2 <= a < 2^(e2+1)
  int k = (e2 * 78913) >> 18;  // floor(e2 · log10 2); the shift floors negatives too
  if (k >= -1 && k <= kMaxPower && a >= kPow10[k + 1]) ++k;
  if (k < -1 && a * kPow10[-k - 1] >= 1.0) ++k;  // 10^-(k+1) is inexact, so scale up instead
  return k;
}

// The exact, slower path, into a buffer of its own: the caller's room is what the header
// promises, not what to_chars would need for any value.
char* slow(char* out, double v, std::chars_format f, int precision) {
  char buf[400];
  const std::to_chars_result r = std::to_chars(buf, buf + sizeof buf, v, f, precision);
  const std::size_t n = static_cast<std::size_t>(r.ptr - buf);
  std::memcpy(out, buf, n);
  return out + n;
}

}  // namespace

namespace {

// A number on its way to "%.9g": its nine significant digits d and decimal exponent k, or
// `fast` false when it takes the slow path.
struct Decomposed {
  std::uint32_t d;
  int k;
  bool fast;
};

[[gnu::always_inline]] inline Decomposed decompose(double v) {
  double a = std::fabs(v);
  bool fast =
      std::endian::native == std::endian::little && std::isnormal(v) && a >= 1e-14 && a < 1e9;
  if (!fast) a = 1;  // keeps the arithmetic below in range; its result is not used
  int k = decimal_exponent(a);
  if (8 - k > kMaxPower) [[unlikely]] {  // just above 1e-14, with the estimate one low
    fast = false;
    k = 8 - kMaxPower;
  }
  std::uint64_t d = scaled_round(a, 8 - k);
  // A tenth digit: the exponent estimate was low, or rounding carried (9.999999996 -> 10).
  if (d >= 1000000000u) [[unlikely]] {
    ++k;
    if (8 - k < 0) return {0, 0, false};
    d = scaled_round(a, 8 - k);
  }
  fast = fast && d >= 100000000u && d < 1000000000u;
  return {static_cast<std::uint32_t>(d), k, fast};
}

// Prints a fast-path number. The digits stay in a register and every store has a fixed size:
// copies of variable length are library calls, and reading back bytes just stored in pieces
// stalls the pipeline; either would cost more than all the arithmetic.
[[gnu::always_inline]] inline char* emit(char* out, bool negative, std::uint32_t d, int k) {
  if (negative) *out++ = '-';
  const char top = static_cast<char>('0' + d / 100000000u);
  const std::uint64_t w = ascii8(d % 100000000u);
  // Significant digits: %g drops trailing zeros (and a bare decimal point).
  const std::uint64_t nonzero = w ^ 0x3030303030303030u;
  const int digits = nonzero == 0 ? 1 : 9 - std::countl_zero(nonzero) / 8;
  if (k < -4) {  // d.ddde-XX (k >= 9 never comes here)
    out[0] = top;
    out[1] = '.';
    std::memcpy(out + 2, &w, 8);
    out += digits > 1 ? digits + 1 : 1;
    out[0] = 'e';
    out[1] = '-';
    std::memcpy(out + 2, kPairs + 2 * (-k), 2);
    return out + 4;
  }
  if (k < 0) {  // 0.ddd to 0.000ddd
    std::memcpy(out, "0.000", 5);
    out += 1 - k;
    out[0] = top;
    std::memcpy(out + 1, &w, 8);
    return out + digits;
  }
  // Up to nine digits before the point, the zeros of w filling up to it.
  const int before = k + 1;
  out[0] = top;
  std::memcpy(out + 1, &w, 8);
  if (digits <= before) return out + before;
  out[before] = '.';
  const std::uint64_t after = w >> (8 * (before - 1));
  std::memcpy(out + before + 1, &after, 8);
  return out + digits + 1;
}

}  // namespace

char* write_g9(char* out, double v) {
  const Decomposed n = decompose(v);
  return n.fast ? emit(out, v < 0, n.d, n.k) : slow(out, v, std::chars_format::general, 9);
}

char* write_g9_list(char* out, const double* v, std::size_t count, char separator) {
  // In blocks: all the arithmetic of a block first, then the printing. The numbers'
  // dependency chains are long and independent, and this way the processor overlaps them
  // (about a third faster than number by number).
  constexpr std::size_t kBlock = 16;
  Decomposed n[kBlock];
  for (std::size_t begin = 0; begin < count; begin += kBlock) {
    const std::size_t size = std::min(kBlock, count - begin);
    for (std::size_t j = 0; j < size; ++j) n[j] = decompose(v[begin + j]);
    for (std::size_t j = 0; j < size; ++j) {
      *out++ = separator;
      const double x = v[begin + j];
      out = n[j].fast ? emit(out, x < 0, n[j].d, n[j].k)
                      : slow(out, x, std::chars_format::general, 9);
    }
  }
  return out;
}

char* write_f6(char* out, double v) {
  const double a = std::fabs(v);
  if (std::endian::native != std::endian::little || !std::isfinite(v) || !(a < 1e3))
    return slow(out, v, std::chars_format::fixed, 6);
  const std::uint64_t d = a == 0 ? 0 : scaled_round(a, 6);
  if (d == 0 && std::signbit(v)) return slow(out, v, std::chars_format::fixed, 6);  // "-0.000000"
  if (v < 0) *out++ = '-';
  out = std::to_chars(out, out + 16, d / 1000000u).ptr;
  *out++ = '.';
  // The six decimals are the last six of eight.
  const std::uint64_t w = ascii8(static_cast<std::uint32_t>(d % 1000000u)) >> 16;
  std::memcpy(out, &w, 8);
  return out + 6;
}

std::string g9_string(double v) {
  char buf[48];
  return std::string(buf, write_g9(buf, v));
}

}  // namespace ftc::tune::detail
