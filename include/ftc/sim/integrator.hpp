#pragma once
// Classical fourth-order Runge–Kutta step for dx/dt = F(t, x).
//
//   k1 = F(t, x), k2 = F(t + h/2, x + h/2 k1), k3 = F(t + h/2, x + h/2 k2), k4 = F(t + h, x + h k3)
//   x(t + h) = x + h/6 (k1 + 2 k2 + 2 k3 + k4)
//
// The overload taking k1 lets a caller that already evaluated F(t, x) reuse it.
#include <utility>

namespace ftc::sim {

// `t_end` is the time of the last stage, t + h; a caller may pass the same instant computed
// another way (k · Ts for the end of a sample) so that it matches the next step's start exactly.
template <class Vector, class F>
Vector rk4_step(const Vector& x, double t, double h, const Vector& k1, F&& deriv, double t_end) {
  const double h2 = 0.5 * h;
  const Vector x2 = x + h2 * k1;
  const Vector k2 = deriv(t + h2, x2);
  const Vector x3 = x + h2 * k2;
  const Vector k3 = deriv(t + h2, x3);
  const Vector x4 = x + h * k3;
  const Vector k4 = deriv(t_end, x4);
  Vector sum = k1 + 2.0 * k2;
  sum += 2.0 * k3;
  sum += k4;
  return x + (h / 6.0) * sum;
}

template <class Vector, class F>
Vector rk4_step(const Vector& x, double t, double h, const Vector& k1, F&& deriv) {
  return rk4_step(x, t, h, k1, std::forward<F>(deriv), t + h);
}

template <class Vector, class F>
Vector rk4_step(const Vector& x, double t, double h, F&& deriv) {
  const Vector k1 = deriv(t, x);
  return rk4_step(x, t, h, k1, std::forward<F>(deriv), t + h);
}

}  // namespace ftc::sim
