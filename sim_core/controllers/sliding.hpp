#pragma once
// Element-wise helpers of sliding-mode control.
//
//   sig^a(x) = |x|^a sign(x)          (sig^a(0) = 0)
//   sigm(s)  = tanh(θ s / 2)          (= (e^{θs} - 1)/(e^{θs} + 1), the paper's smooth sign, but
//                                      without overflow for large θ s)
//   C(X)     = c2 sig^α2(X2) + c1 sig^α1(X1)      the full-order surface term (eq. 8)
#include <cmath>

#include "controllers/sig_power.hpp"
#include "ftc/sim/types.hpp"
#include "lanes/elementary.hpp"

namespace ftc::sim {

// sig^a(x) per component for the fixed exponent of p (the scalar sig is in sig_power.hpp).
template <int N>
FTC_HOT_INLINE Vec<N> sig(const Vec<N>& x, const SigPower& p) {
  Vec<N> r;
  for (int i = 0; i < N; ++i) r[i] = p(x[i]);
  return r;
}

// tanh(y) is ±1 in double precision once |y| > 19.06 (1 - tanh y ≈ 2 e^{-2y} < 2^-54); past
// that point the sign alone gives the same bits without evaluating tanh.
FTC_HOT_INLINE double sigm_scalar(double y) {
  return std::abs(y) > 19.5 ? std::copysign(1.0, y) : lane::tanh(y);
}
template <int N>
FTC_HOT_INLINE Vec<N> sigm(const Vec<N>& s, double theta) {
  const double k = 0.5 * theta;
  Vec<N> r;
  for (int i = 0; i < N; ++i) r[i] = sigm_scalar(k * s[i]);
  return r;
}

// C(X) = c2 sig^α2(X2) + c1 sig^α1(X1) with the gains and exponents of one controller.
class FosmTerm {
 public:
  FosmTerm(double c1, double c2, double alpha1, double alpha2)
      : c1_(c1), c2_(c2), pow1_(alpha1), pow2_(alpha2) {}

  template <int N>
  FTC_HOT_INLINE Vec<N> operator()(const Vec<N>& X1, const Vec<N>& X2) const {
    Vec<N> c = c2_ * sig(X2, pow2_);
    c += c1_ * sig(X1, pow1_);
    return c;
  }

 private:
  double c1_, c2_;
  SigPower pow1_, pow2_;
};

}  // namespace ftc::sim
