#pragma once
// The hexarotor's f(X), G and G⁺ over the lane type T (ftc/sim/hexarotor.hpp gives the
// equations): the class and its lanes (plants/hexarotor_lanes.cpp) evaluate the same operations.
// Private to sim_core.
#include "ftc/sim/hexarotor.hpp"
#include "lanes/lane.hpp"

namespace ftc::sim {
inline namespace FTC_ISA_NS {

// sin α_i, cos α_i for α_i = 30° + 60° (i − 1), and the spin sign σ_i.
inline constexpr double kHexSin[6] = {0.5, 1.0, 0.5, -0.5, -1.0, -0.5};
inline constexpr double kHexCos[6] = {0.8660254037844386,  0.0, -0.8660254037844386,
                                      -0.8660254037844386, 0.0, 0.8660254037844386};
inline constexpr double kHexSpin[6] = {1.0, -1.0, 1.0, -1.0, 1.0, -1.0};

// A(k, i): roll l sin α_i, pitch −l cos α_i, yaw σ_i κ.
template <class T>
FTC_HOT_INLINE T hexarotor_torque(int k, int i, const T& l, const T& kappa) {
  if (k == 0) return l * T(kHexSin[i]);
  if (k == 1) return l * T(-kHexCos[i]);
  return kappa * T(kHexSpin[i]);
}

// G = J⁻¹ A (row-major 3×6) and G⁺ = A⁺ J (row-major 6×3), I = (Ix, Iy, Iz).
template <class T>
void hexarotor_input(const T (&I)[3], const T& l, const T& kappa, T* G, T* G_pinv) {
  const T d[3] = {T(3.0) * l * l, T(3.0) * l * l, T(6.0) * kappa * kappa};
  for (int k = 0; k < 3; ++k)
    for (int i = 0; i < 6; ++i) {
      const T a = hexarotor_torque<T>(k, i, l, kappa);
      G[k * 6 + i] = a / I[k];
      G_pinv[i * 3 + k] = (a / d[k]) * I[k];
    }
}

// f(X) = (kx x5 x6, ky x4 x6, kz x4 x5).
template <class T>
FTC_HOT_INLINE void hexarotor_f(const T& kx, const T& ky, const T& kz, const T& p, const T& q,
                                const T& r, T (&out)[3]) {
  out[0] = kx * (q * r);
  out[1] = ky * (p * r);
  out[2] = kz * (p * q);
}

}  // namespace FTC_ISA_NS
}  // namespace ftc::sim
