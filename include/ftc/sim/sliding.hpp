#pragma once
// Element-wise helpers of sliding-mode control.
//
//   sig^a(x) = |x|^a sign(x)          (sig^a(0) = 0)
//   sigm(s)  = tanh(θ s / 2)          (= (e^{θs} - 1)/(e^{θs} + 1), the paper's smooth sign, but
//                                      without overflow for large θ s)
//   C(X)     = c2 sig^α2(X2) + c1 sig^α1(X1)      the full-order surface term (eq. 8)
#include <cmath>

#include "ftc/sim/types.hpp"

namespace ftc::sim {

// |x|^a as exp(a ln|x|): the same value within a few ulp, at about half the cost of std::pow,
// which matters because the controllers evaluate six of these every sample.
inline double sig(double x, double a) {
  if (x == 0.0) return 0.0;
  return std::copysign(std::exp(a * std::log(std::abs(x))), x);
}

inline Vec3 sig(const Vec3& x, double a) { return Vec3(sig(x[0], a), sig(x[1], a), sig(x[2], a)); }

inline Vec3 sigm(const Vec3& s, double theta) {
  const double k = 0.5 * theta;
  return Vec3(std::tanh(k * s[0]), std::tanh(k * s[1]), std::tanh(k * s[2]));
}

inline Vec3 fosm_term(const Vec3& X1, const Vec3& X2, double c1, double c2, double alpha1,
                      double alpha2) {
  // sig() element by element, bit for bit, but with the six logarithms taken before the six
  // exponentials: the CPU overlaps independent libm calls in a row, where each log-exp pair
  // would wait on itself (2-3 % of a simulation's cycles).
  double l[6];
  for (int i = 0; i < 3; ++i) {
    l[i] = X2[i] == 0.0 ? 0.0 : std::log(std::abs(X2[i]));
    l[i + 3] = X1[i] == 0.0 ? 0.0 : std::log(std::abs(X1[i]));
  }
  Vec3 s2, s1;
  for (int i = 0; i < 3; ++i) {
    s2[i] = X2[i] == 0.0 ? 0.0 : std::copysign(std::exp(alpha2 * l[i]), X2[i]);
    s1[i] = X1[i] == 0.0 ? 0.0 : std::copysign(std::exp(alpha1 * l[i + 3]), X1[i]);
  }
  Vec3 c = c2 * s2;
  c += c1 * s1;
  return c;
}

}  // namespace ftc::sim
