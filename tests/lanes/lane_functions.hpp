#pragma once
// The elementary functions evaluated in the SIMD lanes of one instruction set, for
// test_lanes.cpp. Each lanes_<isa>.cpp is compiled for its instruction set; the results go back
// as plain doubles so that the comparison with the scalar code happens in a baseline-compiled
// file.
#include <cstddef>

#include "lanes/elementary.hpp"

namespace ftc::test {

// The functions, in this order, each over all n arguments.
inline constexpr int kLaneFunctions = 7;  // sin, cos, exp, expm1, tanh, log, sig^0.5625

// out[f * n + i] = function f at xs[i]; n must be a multiple of the lane width.
void lanes_sse2(const double* xs, std::size_t n, double* out);
void lanes_avx2(const double* xs, std::size_t n, double* out);
void lanes_avx512(const double* xs, std::size_t n, double* out);

// The same through the scalar (T = double) instances.
inline void lanes_scalar(const double* xs, std::size_t n, double* out) {
  namespace l = ftc::sim::lane;
  for (std::size_t i = 0; i < n; ++i) {
    l::sincos(xs[i], out[0 * n + i], out[1 * n + i]);
    out[2 * n + i] = l::exp(xs[i]);
    out[3 * n + i] = l::expm1(xs[i]);
    out[4 * n + i] = l::tanh(xs[i]);
    out[5 * n + i] = l::log(xs[i]);
    out[6 * n + i] = l::sig(xs[i], 0.5625);
  }
}

#if defined(FTC_LANES_XSIMD)
// The body of each lanes_<isa>: batches of A.
template <class A>
void lanes_for(const double* xs, std::size_t n, double* out) {
  namespace l = ftc::sim::lane;
  using B = xsimd::batch<double, A>;
  for (std::size_t i = 0; i < n; i += B::size) {
    const B x = B::load_unaligned(xs + i);
    B s, c;
    l::sincos(x, s, c);
    s.store_unaligned(out + 0 * n + i);
    c.store_unaligned(out + 1 * n + i);
    l::exp(x).store_unaligned(out + 2 * n + i);
    l::expm1(x).store_unaligned(out + 3 * n + i);
    l::tanh(x).store_unaligned(out + 4 * n + i);
    l::log(x).store_unaligned(out + 5 * n + i);
    l::sig(x, B(0.5625)).store_unaligned(out + 6 * n + i);
  }
}
#endif

}  // namespace ftc::test
