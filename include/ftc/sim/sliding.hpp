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
// which matters because the controllers evaluate six of these every sample. Split in two steps
// so that vector callers take all their logarithms before their exponentials: the CPU overlaps
// independent libm calls in a row, where each log-exp pair would wait on itself.
inline double log_abs(double x) { return x == 0.0 ? 0.0 : std::log(std::abs(x)); }
// sig^a(x) given l = log_abs(x).
inline double sig_from_log(double x, double l, double a) {
  return x == 0.0 ? 0.0 : std::copysign(std::exp(a * l), x);
}
inline double sig(double x, double a) { return sig_from_log(x, log_abs(x), a); }

inline Vec3 log_abs(const Vec3& x) { return Vec3(log_abs(x[0]), log_abs(x[1]), log_abs(x[2])); }
inline Vec3 sig_from_log(const Vec3& x, const Vec3& l, double a) {
  return Vec3(sig_from_log(x[0], l[0], a), sig_from_log(x[1], l[1], a),
              sig_from_log(x[2], l[2], a));
}
inline Vec3 sig(const Vec3& x, double a) { return sig_from_log(x, log_abs(x), a); }

inline Vec3 sigm(const Vec3& s, double theta) {
  const double k = 0.5 * theta;
  return Vec3(std::tanh(k * s[0]), std::tanh(k * s[1]), std::tanh(k * s[2]));
}

inline Vec3 fosm_term(const Vec3& X1, const Vec3& X2, double c1, double c2, double alpha1,
                      double alpha2) {
  double l2[3], l1[3];  // the six logarithms first (see sig)
  for (int i = 0; i < 3; ++i) {
    l2[i] = log_abs(X2[i]);
    l1[i] = log_abs(X1[i]);
  }
  Vec3 s2, s1;
  for (int i = 0; i < 3; ++i) {
    s2[i] = sig_from_log(X2[i], l2[i], alpha2);
    s1[i] = sig_from_log(X1[i], l1[i], alpha1);
  }
  Vec3 c = c2 * s2;
  c += c1 * s1;
  return c;
}

}  // namespace ftc::sim
