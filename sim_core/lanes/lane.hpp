#pragma once
// The lane type the simulation core is written over: `double` for one simulation (the runtime
// controller, the scalar oracle) or `xsimd::batch<double, Arch>` for W simulations in lockstep,
// one per SIMD lane. Everything the numerics need beyond + - * / and comparisons is here, with
// one overload per kind of lane, so that the physics and the elementary functions are written
// once and give the same bits in every lane as the scalar code gives.
//
// Only operations that IEEE 754 defines exactly are used (add, multiply, divide, sqrt, compare,
// bit operations): a SIMD lane then rounds exactly as the scalar unit does, on any x86-64 or
// aarch64 CPU. The build turns off FMA contraction (-ffp-contract=off), which would change the
// rounding of a*b + c depending on the instruction set.
//
// Private to sim_core. xsimd is included only where a translation unit defines FTC_LANES_XSIMD
// (the per-ISA kernel files), so the scalar build needs none of it.
#include <bit>
#include <cmath>
#include <cstdint>
#include <type_traits>

#include "ftc/sim/types.hpp"

#if defined(FTC_LANES_XSIMD)
#include <xsimd/xsimd.hpp>
#endif

// Every file that includes this one compiles the lane code for one instruction set, and GCC
// may emit an out-of-line copy of any inline function in it. Were those copies shared between
// files compiled for different instruction sets, the linker could keep an AVX-512 copy for the
// scalar code of a CPU without AVX-512. The inline namespace gives each instruction set's
// instances their own names (kernel files define FTC_ISA_NS; tests/lane_symbols.sh checks it).
#ifndef FTC_ISA_NS
#define FTC_ISA_NS isa_scalar
#endif

namespace ftc::sim::lane {
inline namespace FTC_ISA_NS {

// ---- one lane: double, with bool masks -------------------------------------------------------

template <class T>
struct Traits;

template <>
struct Traits<double> {
  using Mask = bool;
  static constexpr int kWidth = 1;
};

FTC_HOT_INLINE double select(bool m, double a, double b) { return m ? a : b; }
FTC_HOT_INLINE bool all(bool m) { return m; }
FTC_HOT_INLINE bool any(bool m) { return m; }
FTC_HOT_INLINE bool mask_not(bool m) { return !m; }
FTC_HOT_INLINE double sqrt(double x) { return std::sqrt(x); }  // correctly rounded (IEEE 754)
FTC_HOT_INLINE void store(double x, double* p) { *p = x; }
// Lane i of a mask as a bool array (one lane here).
FTC_HOT_INLINE void store_mask(bool m, bool* out) { *out = m; }
FTC_HOT_INLINE double abs(double x) {
  return std::bit_cast<double>(std::bit_cast<std::uint64_t>(x) & ~(1ULL << 63));
}
// |x| with the sign of y, by bits (exact; also for NaN and signed zeros).
FTC_HOT_INLINE double copysign(double x, double y) {
  const std::uint64_t s = std::bit_cast<std::uint64_t>(y) & (1ULL << 63);
  return std::bit_cast<double>((std::bit_cast<std::uint64_t>(x) & ~(1ULL << 63)) | s);
}
// 2^k for an integral k in [-1022, 1023] given as a double.
FTC_HOT_INLINE double pow2i(double k) {
  // k + (2^52 + 1023) holds the biased exponent in its low bits; shifting them up by 52 makes
  // the bits of 2^k.
  const std::uint64_t b = std::bit_cast<std::uint64_t>(k + 0x1p52 + 1023.0);
  return std::bit_cast<double>(b << 52);
}
// The biased exponent field of x (as a double) and x's significand scaled into [1, 2) (for a
// normal x > 0).
FTC_HOT_INLINE double biased_exponent(double x) {
  return static_cast<double>(std::bit_cast<std::uint64_t>(x) >> 52 & 0x7ff);
}
FTC_HOT_INLINE double significand(double x) {
  const std::uint64_t b = std::bit_cast<std::uint64_t>(x);
  return std::bit_cast<double>((b & 0x000FFFFFFFFFFFFFULL) | 0x3FF0000000000000ULL);
}
FTC_HOT_INLINE std::int64_t bits_of(double x) { return std::bit_cast<std::int64_t>(x); }
FTC_HOT_INLINE double gather_at(const double* table, std::int64_t i) { return table[i]; }
FTC_HOT_INLINE double lane_of(double x, int) { return x; }
FTC_HOT_INLINE void set_lane(double& x, int, double v) { x = v; }
FTC_HOT_INLINE bool mask_lane(bool m, int) { return m; }
// NaN test that means the same for scalars and lanes (x != x is an ordered comparison for some
// SIMD instruction sets, false for NaN).
FTC_HOT_INLINE bool is_nan(double x) { return x != x; }

// Round to the nearest integer, ties to even, for |x| < 2^51, in plain IEEE arithmetic (the
// same bits in every lane and on every CPU, without depending on the rounding instruction).
template <class T>
FTC_HOT_INLINE T round_to_int(T x) {
  const T shifter(0x1.8p52);
  return (x + shifter) - shifter;
}

#if defined(FTC_LANES_XSIMD)

// ---- W lanes: xsimd::batch<double, A>, with batch_bool masks ---------------------------------

template <class A>
struct Traits<xsimd::batch<double, A>> {
  using Mask = xsimd::batch_bool<double, A>;
  static constexpr int kWidth = static_cast<int>(xsimd::batch<double, A>::size);
};

template <class A>
FTC_HOT_INLINE xsimd::batch<double, A> select(const xsimd::batch_bool<double, A>& m,
                                              const xsimd::batch<double, A>& a,
                                              const xsimd::batch<double, A>& b) {
  return xsimd::select(m, a, b);
}
template <class A>
FTC_HOT_INLINE bool all(const xsimd::batch_bool<double, A>& m) {
  return xsimd::all(m);
}
template <class A>
FTC_HOT_INLINE bool any(const xsimd::batch_bool<double, A>& m) {
  return xsimd::any(m);
}
template <class A>
FTC_HOT_INLINE xsimd::batch_bool<double, A> mask_not(const xsimd::batch_bool<double, A>& m) {
  return !m;
}
template <class A>
FTC_HOT_INLINE xsimd::batch<double, A> sqrt(const xsimd::batch<double, A>& x) {
  return xsimd::sqrt(x);  // the vector square root instruction, correctly rounded like sqrtsd
}
// A batch to W consecutive doubles (unaligned; load_lanes below is the way back).
template <class A>
FTC_HOT_INLINE void store(const xsimd::batch<double, A>& x, double* p) {
  x.store_unaligned(p);
}
template <class A>
FTC_HOT_INLINE void store_mask(const xsimd::batch_bool<double, A>& m, bool* out) {
  m.store_unaligned(out);
}
// The magnitude bits (all but the sign) as a double, for masking.
template <class A>
FTC_HOT_INLINE xsimd::batch<double, A> magnitude_mask() {
  return xsimd::batch<double, A>(std::bit_cast<double>(~(1ULL << 63)));
}
template <class A>
FTC_HOT_INLINE xsimd::batch<double, A> abs(const xsimd::batch<double, A>& x) {
  return xsimd::bitwise_and(x, magnitude_mask<A>());
}
template <class A>
FTC_HOT_INLINE xsimd::batch<double, A> copysign(const xsimd::batch<double, A>& x,
                                                const xsimd::batch<double, A>& y) {
  return xsimd::bitwise_or(xsimd::bitwise_and(x, magnitude_mask<A>()),
                           xsimd::bitwise_and(y, xsimd::batch<double, A>(-0.0)));
}
template <class A>
FTC_HOT_INLINE xsimd::batch<double, A> pow2i(const xsimd::batch<double, A>& k) {
  using U = xsimd::batch<std::uint64_t, A>;
  const U b = xsimd::bitwise_cast<U>(k + xsimd::batch<double, A>(0x1p52 + 1023.0));
  return xsimd::bitwise_cast<xsimd::batch<double, A>>(b << 52);
}
template <class A>
FTC_HOT_INLINE xsimd::batch<double, A> biased_exponent(const xsimd::batch<double, A>& x) {
  using U = xsimd::batch<std::uint64_t, A>;
  // The exponent field placed in the low bits of 2^52's significand: (2^52 + e) - 2^52 = e.
  const U e = (xsimd::bitwise_cast<U>(x) >> 52) & U(0x7ff);
  const xsimd::batch<double, A> big(0x1p52);
  return xsimd::bitwise_cast<xsimd::batch<double, A>>(e | xsimd::bitwise_cast<U>(big)) - big;
}
template <class A>
FTC_HOT_INLINE xsimd::batch<double, A> significand(const xsimd::batch<double, A>& x) {
  using U = xsimd::batch<std::uint64_t, A>;
  const U b = xsimd::bitwise_cast<U>(x);
  return xsimd::bitwise_cast<xsimd::batch<double, A>>((b & U(0x000FFFFFFFFFFFFFULL)) |
                                                      U(0x3FF0000000000000ULL));
}
// The bits of x as 64-bit integers, and a table read with integer indices (per lane).
template <class A>
FTC_HOT_INLINE xsimd::batch<std::int64_t, A> bits_of(const xsimd::batch<double, A>& x) {
  return xsimd::bitwise_cast<xsimd::batch<std::int64_t, A>>(x);
}
// xsimd 8.1's batch::gather names its kernel with explicit template arguments that drop the
// AVX2 and AVX-512 overloads, so it always took the generic path: one insert per lane, each
// through an out-of-line mask constructor (7 % of the adaptive controller's time in AVX-512).
// Calling the instruction set's kernel directly gives the gather instruction; the same table
// entries, so the same bits.
template <class A>
FTC_HOT_INLINE xsimd::batch<double, A> gather_at(const double* table,
                                                 const xsimd::batch<std::int64_t, A>& i) {
  if constexpr (std::is_base_of_v<xsimd::avx512f, A> || std::is_base_of_v<xsimd::avx2, A>) {
    return xsimd::kernel::gather<A>(table, i, A{});
  } else {
    alignas(A::alignment()) std::int64_t k[xsimd::batch<double, A>::size];
    alignas(A::alignment()) double v[xsimd::batch<double, A>::size];
    i.store_aligned(k);
    for (std::size_t l = 0; l < xsimd::batch<double, A>::size; ++l) v[l] = table[k[l]];
    return xsimd::batch<double, A>::load_aligned(v);
  }
}
template <class A>
FTC_HOT_INLINE xsimd::batch_bool<double, A> is_nan(const xsimd::batch<double, A>& x) {
  return xsimd::isnan(x);
}
template <class A>
FTC_HOT_INLINE double lane_of(const xsimd::batch<double, A>& x, int i) {
  alignas(A::alignment()) double v[xsimd::batch<double, A>::size];
  x.store_aligned(v);
  return v[i];
}
template <class A>
FTC_HOT_INLINE void set_lane(xsimd::batch<double, A>& x, int i, double value) {
  alignas(A::alignment()) double v[xsimd::batch<double, A>::size];
  x.store_aligned(v);
  v[i] = value;
  x = xsimd::batch<double, A>::load_aligned(v);
}
template <class A>
FTC_HOT_INLINE bool mask_lane(const xsimd::batch_bool<double, A>& m, int i) {
  alignas(A::alignment()) bool v[xsimd::batch<double, A>::size];
  m.store_aligned(v);
  return v[i];
}

#endif

// The largest integer ≤ x, for |x| < 2^51.
template <class T>
FTC_HOT_INLINE T floor_int(T x) {
  const T r = lane::round_to_int(x);
  return lane::select(r > x, r - T(1.0), r);
}

template <class T>
inline constexpr int kWidth = Traits<T>::kWidth;
template <class T>
using Mask = typename Traits<T>::Mask;

// W doubles from p into a lane value, for T = double as well.
template <class T>
FTC_HOT_INLINE T load_lanes(const double* p) {
  if constexpr (std::is_same_v<T, double>)
    return *p;
  else
    return T::load_unaligned(p);
}

}  // namespace FTC_ISA_NS
}  // namespace ftc::sim::lane
