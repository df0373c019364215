#pragma once
// The rigid body's f(X), G(X) u and G⁺(X) over the lane type T (ftc/sim/rigid_body.hpp gives
// the equations): the class (T = double, sines from math::sincos) and its lanes
// (plants/rigid_body_lanes.cpp, sines from angle trackers) evaluate the same operations.
// Private to sim_core.
//
// body_f, body_input and body_pinv are calls, not inlined into the loop as the other plants' are:
// with up to 8 actuators and each lane's choice of form they are large, and inlined into the
// eight loops of a kernel file (4 controller types, shared inputs or not) they made GCC 12 spend
// 88 s on the AVX2 copy alone (463 s for the four copies); as calls, 35 s (133 s), on the 2-core
// VM. The price, in BM_RigidBodyLanes and BM_QuadXLanes interleaved 5 times against the inlined
// build there: AVX-512 unchanged (medians 0.99 to 1.01 of before), but the rigid body's AVX2
// copy 1.05 to 1.26 times slower in its medians, within overlapping ranges; inlining back only
// the cheap body_input is the first thing to try if that matters.
#include "ftc/sim/rigid_body.hpp"
#include "lanes/lane.hpp"

namespace ftc::sim {
inline namespace FTC_ISA_NS {

// One side of the plant (the simulated truth or the controller's model) as its constants give
// it (RigidBodyConstants), for T lanes.
template <class T>
struct BodyTerms {
  static constexpr int MA = kMaxBodyActuators;
  bool euler = true;
  int m = 0;
  // Each lane's own J decides between the diagonal operations (the hexarotor's) and the full
  // ones, never the pack's mix of lanes: a lane gives the same bits in any pack, on any SIMD
  // width. `all_diagonal` and `any_diagonal` skip the form no lane needs.
  lane::Mask<T> diagonal;
  bool all_diagonal = true, any_diagonal = true;
  T J[9], Ji[9];  // J and J⁻¹, row-major
  T k[3];         // kx, ky, kz (the diagonal form)
  T D[3 * MA];    // row-major 3×8
  T G0[3 * MA];   // J⁻¹ D, row-major 3×8: G itself with body rates
  T P[MA * 3];    // D⁺, row-major 8×3

  // `c(i)`: constant i (RigidBodyConstants) of every lane.
  template <class C>
  void load(const C& c) {
    using K = RigidBodyConstants;
    euler = lane::lane_of(c(K::kEuler), 0) != 0.0;
    m = static_cast<int>(lane::lane_of(c(K::kM), 0));
    diagonal = c(K::kDiagonal) != T(0.0);
    all_diagonal = lane::all(diagonal);
    any_diagonal = lane::any(diagonal);
    const T xx = c(K::kJ), yy = c(K::kJ + 1), zz = c(K::kJ + 2);
    const T xy = c(K::kJ + 3), xz = c(K::kJ + 4), yz = c(K::kJ + 5);
    const T full[9] = {xx, xy, xz, xy, yy, yz, xz, yz, zz};
    for (int i = 0; i < 9; ++i) J[i] = full[i];
    k[0] = (yy - zz) / xx;
    k[1] = (zz - xx) / yy;
    k[2] = (xx - yy) / zz;
    // J⁻¹ by its adjugate (symmetric), over the determinant by the first row.
    const T a00 = yy * zz - yz * yz, a01 = xz * yz - xy * zz, a02 = xy * yz - xz * yy;
    const T a11 = xx * zz - xz * xz, a12 = xy * xz - xx * yz, a22 = xx * yy - xy * xy;
    const T det = (xx * a00 + xy * a01) + xz * a02;
    const T adj[9] = {a00, a01, a02, a01, a11, a12, a02, a12, a22};
    for (int i = 0; i < 9; ++i) Ji[i] = adj[i] / det;
    for (int i = 0; i < 3 * MA; ++i) D[i] = c(K::kD + i);
    for (int i = 0; i < MA * 3; ++i) P[i] = c(K::kDpinv + i);
    // With J diagonal, A(k, j) / I_k: the hexarotor's G.
    for (int r = 0; r < 3; ++r)
      for (int j = 0; j < MA; ++j)
        G0[r * MA + j] = lane::select(diagonal, D[r * MA + j] / J[4 * r],
                                      (Ji[3 * r] * D[j] + Ji[3 * r + 1] * D[MA + j]) +
                                          Ji[3 * r + 2] * D[2 * MA + j]);
  }

  // The diagonal form in the lanes whose J is diagonal, the full form in the others; each form
  // is evaluated only when some lane needs it.
  template <class Diag, class Full>
  FTC_HOT_INLINE T per_lane(Diag&& d, Full&& f) const {
    if (all_diagonal) return d();
    if (!any_diagonal) return f();
    return lane::select(diagonal, d(), f());
  }

  // h = J⁻¹ (−ω × J ω) = J⁻¹ (J ω × ω).
  FTC_HOT_INLINE void gyro(const T (&w)[3], T (&h)[3]) const {
    T full[3] = {T(0.0), T(0.0), T(0.0)};
    if (!all_diagonal) {
      const T Jw[3] = {(J[0] * w[0] + J[1] * w[1]) + J[2] * w[2],
                       (J[3] * w[0] + J[4] * w[1]) + J[5] * w[2],
                       (J[6] * w[0] + J[7] * w[1]) + J[8] * w[2]};
      const T c[3] = {Jw[1] * w[2] - Jw[2] * w[1], Jw[2] * w[0] - Jw[0] * w[2],
                      Jw[0] * w[1] - Jw[1] * w[0]};
      for (int r = 0; r < 3; ++r)
        full[r] = (Ji[3 * r] * c[0] + Ji[3 * r + 1] * c[1]) + Ji[3 * r + 2] * c[2];
    }
    const T wp[3] = {w[1] * w[2], w[0] * w[2], w[0] * w[1]};
    for (int r = 0; r < 3; ++r)
      h[r] = per_lane([&] { return k[r] * wp[r]; }, [&] { return full[r]; });
  }
};

// sin and cos of roll and pitch, and 1 / cos pitch, at one state.
template <class T>
struct BodyTrig {
  T sf, cf, st, ct, ict;
};

// W y (body rates from Euler rates).
template <class T>
FTC_HOT_INLINE void euler_W(const BodyTrig<T>& g, const T (&y)[3], T (&w)[3]) {
  w[0] = y[0] - g.st * y[2];
  w[1] = g.cf * y[1] + (g.sf * g.ct) * y[2];
  w[2] = (g.cf * g.ct) * y[2] - g.sf * y[1];
}

// W⁻¹ y.
template <class T>
FTC_HOT_INLINE void euler_W_inv(const BodyTrig<T>& g, const T (&y)[3], T (&z)[3]) {
  const T s = (g.sf * y[1] + g.cf * y[2]) * g.ict;
  z[0] = y[0] + g.st * s;
  z[1] = g.cf * y[1] - g.sf * y[2];
  z[2] = s;
}

// f(X), x = (φ, θ, ψ, φ̇, θ̇, ψ̇); `g` the trigonometry of x (unused with body rates).
template <class T>
[[gnu::noinline]] void body_f(const BodyTerms<T>& b, const BodyTrig<T>& g, const T* x, T (&f)[3]) {
  const T r[3] = {x[3], x[4], x[5]};
  if (!b.euler) {
    b.gyro(r, f);
    return;
  }
  T w[3], h[3];
  euler_W(g, r, w);
  b.gyro(w, h);
  // Ẇ Ẋ1.
  const T pd = r[0], td = r[1], yd = r[2];
  const T v[3] = {-(g.ct * td) * yd,  //
                  (g.cf * g.ct * pd - g.sf * g.st * td) * yd - (g.sf * pd) * td,
                  -((g.cf * pd) * td) - (g.sf * g.ct * pd + g.cf * g.st * td) * yd};
  const T y[3] = {h[0] - v[0], h[1] - v[1], h[2] - v[2]};
  euler_W_inv(g, y, f);
}

// G(X) u = W⁻¹ (J⁻¹ D) u, (J⁻¹ D) u summed over the first m columns in order.
template <class T>
[[gnu::noinline]] void body_input(const BodyTerms<T>& b, const BodyTrig<T>& g, const T* u,
                                  T (&Gu)[3]) {
  constexpr int MA = kMaxBodyActuators;
  T a[3];
  for (int r = 0; r < 3; ++r) {
    T s = b.G0[r * MA] * u[0];
    for (int j = 1; j < b.m; ++j) s = s + b.G0[r * MA + j] * u[j];
    a[r] = s;
  }
  if (!b.euler) {
    for (int r = 0; r < 3; ++r) Gu[r] = a[r];
    return;
  }
  euler_W_inv(g, a, Gu);
}

// G⁺(X) = D⁺ J W, row-major 8×3 (rows past m zero). With a diagonal J, J W's row k is I_k times
// W's, and with body rates (W = I) G⁺(j, k) = D⁺(j, k) I_k: the hexarotor's A⁺ J.
template <class T>
[[gnu::noinline]] void body_pinv(const BodyTerms<T>& b, const BodyTrig<T>& g, T* out) {
  constexpr int MA = kMaxBodyActuators;
  const T I3[9] = {T(1.0), T(0.0), T(0.0), T(0.0), T(1.0), T(0.0), T(0.0), T(0.0), T(1.0)};
  const T Wx[9] = {T(1.0), T(0.0), -g.st, T(0.0), g.cf, g.sf * g.ct, T(0.0), -g.sf, g.cf * g.ct};
  const T* W = b.euler ? Wx : I3;
  T JW[9];
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c)
      JW[3 * r + c] = b.per_lane(
          [&] { return b.J[4 * r] * W[3 * r + c]; },
          [&] {
            return (b.J[3 * r] * W[c] + b.J[3 * r + 1] * W[3 + c]) + b.J[3 * r + 2] * W[6 + c];
          });
  for (int j = 0; j < MA; ++j)
    for (int c = 0; c < 3; ++c)
      out[j * 3 + c] = b.euler ? (b.P[j * 3] * JW[c] + b.P[j * 3 + 1] * JW[3 + c]) +
                                     b.P[j * 3 + 2] * JW[6 + c]
                               : b.per_lane([&] { return b.P[j * 3 + c] * b.J[4 * c]; },
                                            [&] {
                                              return (b.P[j * 3] * JW[c] +
                                                      b.P[j * 3 + 1] * JW[3 + c]) +
                                                     b.P[j * 3 + 2] * JW[6 + c];
                                            });
}

}  // namespace FTC_ISA_NS
}  // namespace ftc::sim
