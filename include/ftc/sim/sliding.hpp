#pragma once
// Element-wise helpers of sliding-mode control.
//
//   sig^a(x) = |x|^a sign(x)          (sig^a(0) = 0)
//   sigm(s)  = tanh(θ s / 2)          (= (e^{θs} - 1)/(e^{θs} + 1), the paper's smooth sign, but
//                                      without overflow for large θ s)
//   C(X)     = c2 sig^α2(X2) + c1 sig^α1(X1)      the full-order surface term (eq. 8)
#include <cmath>

#include "ftc/sim/sig_power.hpp"
#include "ftc/sim/types.hpp"

namespace ftc::sim {

// sig^a(x) per component for the fixed exponent of p (the scalar sig is in sig_power.hpp).
inline Vec3 sig(const Vec3& x, const SigPower& p) { return Vec3(p(x[0]), p(x[1]), p(x[2])); }

// tanh(y) is ±1 in double precision once |y| > 19.06 (1 - tanh y ≈ 2 e^{-2y} < 2^-54); past
// that point the sign alone gives the same bits without a call into libm.
inline double sigm_scalar(double y) {
  return std::abs(y) > 19.5 ? std::copysign(1.0, y) : std::tanh(y);
}
inline Vec3 sigm(const Vec3& s, double theta) {
  const double k = 0.5 * theta;
  return Vec3(sigm_scalar(k * s[0]), sigm_scalar(k * s[1]), sigm_scalar(k * s[2]));
}

// C(X) = c2 sig^α2(X2) + c1 sig^α1(X1) with the gains and exponents of one controller.
class FosmTerm {
 public:
  FosmTerm(double c1, double c2, double alpha1, double alpha2)
      : c1_(c1), c2_(c2), pow1_(alpha1), pow2_(alpha2) {}

  Vec3 operator()(const Vec3& X1, const Vec3& X2) const {
    Vec3 c = c2_ * sig(X2, pow2_);
    c += c1_ * sig(X1, pow1_);
    return c;
  }

 private:
  double c1_, c2_;
  SigPower pow1_, pow2_;
};

}  // namespace ftc::sim
