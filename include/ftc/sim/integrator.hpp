#pragma once
// Classical fourth-order Runge–Kutta step for dx/dt = F(t, x).
//
//   k1 = F(t, x), k2 = F(t + h/2, x + h/2 k1), k3 = F(t + h/2, x + h/2 k2), k4 = F(t + h, x + h k3)
//   x(t + h) = x + h/6 (k1 + 2 k2 + 2 k3 + k4)

#include "ftc/sim/types.hpp"

namespace ftc::sim {

// The step with k1 already known and the stage functions bound to their instants:
// mid(x) = F(t + h/2, x) and end(x) = F(t + h, x). A caller with time-dependent inputs
// evaluates them once per instant (the midpoint serves two stages) and binds them here.
template <class Vector, class Mid, class End>
FTC_HOT_INLINE Vector rk4_step(const Vector& x, double h, const Vector& k1, Mid&& mid, End&& end) {
  const double h2 = 0.5 * h;
  const Vector x2 = x + h2 * k1;
  const Vector k2 = mid(x2);
  const Vector x3 = x + h2 * k2;
  const Vector k3 = mid(x3);
  const Vector x4 = x + h * k3;
  const Vector k4 = end(x4);
  Vector sum = k1 + 2.0 * k2;
  sum += 2.0 * k3;
  sum += k4;
  return x + (h / 6.0) * sum;
}

template <class Vector, class F>
Vector rk4_step(const Vector& x, double t, double h, F&& deriv) {
  return rk4_step(
      x, h, deriv(t, x), [&](const Vector& s) { return deriv(t + 0.5 * h, s); },
      [&](const Vector& s) { return deriv(t + h, s); });
}

}  // namespace ftc::sim
