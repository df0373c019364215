#pragma once
// Classical fourth-order Runge–Kutta step for dx/dt = F(t, x) over the loop's Eigen vectors:
// rk4_advance (ftc/sim/rk4.hpp) gives the equations and the one order of operations.

#include "ftc/sim/rk4.hpp"
#include "ftc/sim/types.hpp"

namespace ftc::sim {

// The step with k1 already known and the stage functions bound to their instants:
// mid(x) = F(t + h/2, x) and end(x) = F(t + h, x). A caller with time-dependent inputs
// evaluates them once per instant (the midpoint serves two stages) and binds them here. The
// operations are rk4_advance's, which the lanes' kernel runs too.
template <class Vector, class Mid, class End>
FTC_HOT_INLINE Vector rk4_step(const Vector& x, double h, const Vector& k1, Mid&& mid, End&& end) {
  Vector next = x;
  rk4_advance(next, k1, 0.5 * h, h, h / 6.0, mid, end);
  return next;
}

template <class Vector, class F>
Vector rk4_step(const Vector& x, double t, double h, F&& deriv) {
  return rk4_step(
      x, h, deriv(t, x), [&](const Vector& s) { return deriv(t + 0.5 * h, s); },
      [&](const Vector& s) { return deriv(t + h, s); });
}

}  // namespace ftc::sim
