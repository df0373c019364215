#pragma once
// The classical fourth-order Runge–Kutta step for dX/dt = F(t, X), written once: the closed
// loop's state of lanes (sim_core/lanes/closed_loop.hpp) and, through rk4_step, an Eigen state
// (integrator.hpp).
//
//   k1 = F(t, X), k2 = F(t + h/2, X + h/2 k1), k3 = F(t + h/2, X + h/2 k2), k4 = F(t + h, X + h k3)
//   X(t + h) = X + h/6 (k1 + 2 k2 + 2 k3 + k4)
//
// Element by element, in this order of operations, so that a lane of the kernel gives the bits of
// the scalar loop (the build contracts no multiply-add). It includes nothing: the kernel compiles
// it once per instruction set without pulling in Eigen.

namespace ftc::sim {

// Advances `x` by one step of length h with k1 = F(t, x) known and the stages bound to their
// instants: mid(s) = F(t + h/2, s) (two stages share it) and end(s) = F(t + h, s). State is
// indexable and has size(); Real is its element type (double, or a lane of doubles), and
// h2 = h/2, h6 = h/6 are formed by the caller in double.
template <class State, class Real, class Mid, class End>
#if defined(__GNUC__)
[[gnu::always_inline]]
#endif
inline void rk4_advance(State& x, const State& k1, Real h2, Real h, Real h6, Mid&& mid,
                        End&& end) {
  const int n = static_cast<int>(x.size());
  State xs = x;  // sized like x (a dynamic Eigen vector too)
  for (int r = 0; r < n; ++r) xs[r] = x[r] + h2 * k1[r];
  const State k2 = mid(xs);
  for (int r = 0; r < n; ++r) xs[r] = x[r] + h2 * k2[r];
  const State k3 = mid(xs);
  for (int r = 0; r < n; ++r) xs[r] = x[r] + h * k3[r];
  const State k4 = end(xs);
  for (int r = 0; r < n; ++r) {
    Real sum = k1[r] + Real(2.0) * k2[r];
    sum = sum + Real(2.0) * k3[r];
    sum = sum + k4[r];
    x[r] = x[r] + h6 * sum;
  }
}

}  // namespace ftc::sim
