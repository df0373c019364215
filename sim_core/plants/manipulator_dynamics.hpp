#pragma once
// The arm's f(X) and G(X) over the lane type T (ftc/sim/manipulator.hpp gives the equations):
// Manipulator::f and G and the closed loop's lanes (plants/manipulator_lanes.cpp) evaluate the
// same operations. a1, a2, a3, b1, b2 are Manipulator::f_constants(); s and c the sines and
// cosines of q1 and q2. Private to sim_core.
#include "ftc/sim/manipulator.hpp"
#include "lanes/lane.hpp"
#include "sincos.hpp"

namespace ftc::sim {

// f at joint angles that move in small steps, from one angle tracker per joint: the simulator
// owns one per run.
struct Manipulator::Workspace {
  std::array<SinCosTracker, 2> trig{};
};

inline namespace FTC_ISA_NS {

// M(q)⁻¹ = [[d11, d12], [d12, d22]] at cos q2.
template <class T>
struct ArmInverseMass {
  T d11, d12, d22;
};
template <class T>
FTC_HOT_INLINE ArmInverseMass<T> arm_inverse_mass(const T& a1, const T& a2, const T& a3,
                                                  const T& c2) {
  const T m11 = a1 + T(2.0) * a2 * c2, m12 = a3 + a2 * c2, m22 = a3;
  const T k = T(1.0) / (m11 * m22 - m12 * m12);
  return {m22 * k, -m12 * k, m11 * k};
}

// f(X) = −M⁻¹ (C q̇ + g).
template <class T>
FTC_HOT_INLINE void arm_f(const T& a2, const T& b1, const T& b2, const ArmInverseMass<T>& Mi,
                          const T& s1, const T& c1, const T& s2, const T& c2, const T& w1,
                          const T& w2, T (&out)[2]) {
  const T c12 = c1 * c2 - s1 * s2;  // cos(q1 + q2) from the sines and cosines at hand
  const T h = a2 * s2;
  const T g2 = b2 * c12;
  // −(C q̇ + g).
  const T r1 = h * (T(2.0) * w1 * w2 + w2 * w2) - (b1 * c1 + g2);
  const T r2 = -h * w1 * w1 - g2;
  out[0] = Mi.d11 * r1 + Mi.d12 * r2;
  out[1] = Mi.d12 * r1 + Mi.d22 * r2;
}

// G⁺ = B⁺ M(q), row-major 3×2, B⁺ = [[2, −1], [−1, 2], [1, 1]] / 3: as Eigen forms
// actuator_pinv() * mass_matrix(q), out(i, k) = B⁺(i, 0) M(0, k) + B⁺(i, 1) M(1, k).
template <class T>
FTC_HOT_INLINE void arm_pinv(const T& a1, const T& a2, const T& a3, const T& c2, T* out) {
  const T m11 = a1 + T(2.0) * a2 * c2, m12 = a3 + a2 * c2, m22 = a3;
  const double bp[3][2] = {{2.0 / 3.0, -1.0 / 3.0}, {-1.0 / 3.0, 2.0 / 3.0}, {1.0 / 3.0, 1.0 / 3.0}};
  const T m[2][2] = {{m11, m12}, {m12, m22}};
  for (int i = 0; i < 3; ++i)
    for (int k = 0; k < 2; ++k) out[i * 2 + k] = T(bp[i][0]) * m[0][k] + T(bp[i][1]) * m[1][k];
}

}  // namespace FTC_ISA_NS

FTC_HOT_INLINE Manipulator::Vector Manipulator::f(const State& x, Workspace& ws) const {
  double s1, c1, s2, c2;
  ws.trig[0].eval(x[0], s1, c1);
  ws.trig[1].eval(x[1], s2, c2);
  double out[2];
  arm_f<double>(a2_, b1_, b2_, arm_inverse_mass<double>(a1_, a2_, a3_, c2), s1, c1, s2, c2, x[2],
                x[3], out);
  return Vector(out[0], out[1]);
}

FTC_HOT_INLINE Manipulator::InputMatrix Manipulator::G(const State& x, Workspace& ws) const {
  double s2, c2;
  ws.trig[1].eval(x[1], s2, c2);
  const ArmInverseMass<double> Mi = arm_inverse_mass<double>(a1_, a2_, a3_, c2);
  InputMatrix g;
  g << Mi.d11, Mi.d12, Mi.d11 + Mi.d12,  //
      Mi.d12, Mi.d22, Mi.d12 + Mi.d22;
  return g;
}

}  // namespace ftc::sim
