#pragma once
// Planar two-link robot arm in a vertical plane, with three actuators (n = 2, m = 3).
//
// State: X1 = q = (q1, q2) in rad, q1 of link 1 from the horizontal and q2 of link 2 relative
// to link 1 (counter-clockwise positive); X2 = q̇ in rad/s. The joint-space dynamics (Spong,
// Hutchinson & Vidyasagar, Robot Modeling and Control, §7.4; Slotine & Li §9.1) are
//
//   M(q) q̈ + C(q, q̇) q̇ + g(q) = τ = B u
//
//   M11 = m1 lc1² + m2 (l1² + lc2² + 2 l1 lc2 cos q2) + I1 + I2
//   M12 = M21 = m2 (lc2² + l1 lc2 cos q2) + I2,   M22 = m2 lc2² + I2          (kg·m²)
//   C q̇ = [ −h (2 q̇1 q̇2 + q̇2²),  h q̇1² ],   h = m2 l1 lc2 sin q2           (N·m)
//   g1  = (m1 lc1 + m2 l1) g0 cos q1 + m2 lc2 g0 cos(q1 + q2)
//   g2  = m2 lc2 g0 cos(q1 + q2)                                             (N·m)
//
// with link masses m_i (kg), lengths l_i (m), distances lc_i from joint i to the centre of mass
// of link i (m), moments of inertia I_i about those centres (kg·m²) and gravity g0 (m/s²). The
// potential energy is V = (m1 lc1 + m2 l1) g0 sin q1 + m2 lc2 g0 sin(q1 + q2), so the arm
// hangs at rest at q = (−π/2, 0); holding q = 0 (stretched out horizontally) takes torque.
// l2 does not enter the dynamics (only lc2 and I2 do); it completes the description of the arm.
//
// u ∈ R³ are actuator torques in N·m, mapped onto joint torques by the constant
//
//   B = [ 1 0 1 ]     actuator 1 drives joint 1, actuator 2 joint 2, and actuator 3 is a
//       [ 0 1 1 ]     biarticular actuator applying the same torque to both joints.
//
// The third actuator is there for fault tolerance: B has full row rank with any one column
// removed, so after one actuator is lost (or stuck) the remaining two still reach every joint
// torque. With only the two joint motors, losing one would leave a joint unactuated. (Whether a
// controller that does not know of the fault recovers is another matter: docs/model.md (the
// manipulator section).)
//
// In the paper's form dX2/dt = f(X) + G(X) u + Δ:
//
//   f(X) = −M(q)⁻¹ (C(q, q̇) q̇ + g(q))   (rad/s²),   G(X) = M(q)⁻¹ B   (rad/s² per N·m)
//
// G depends on q2, so the simulator and controllers evaluate it at every state. Its right
// inverse has a closed form: G⁺ = Gᵀ(GGᵀ)⁻¹ = Bᵀ(BBᵀ)⁻¹ M(q) = B⁺ M(q), since M is symmetric;
// no matrix is inverted at run time. M⁻¹ is formed in closed form from
//
//   det M = (m1 lc1² + I1)(m2 lc2² + I2) + m2 l1² (m2 lc2² sin² q2 + I2)   (kg²·m⁴)
//
// which is positive at every q when the masses and inertias are.
#include <array>
#include <cmath>
#include <string>

#include "ftc/sim/elementary.hpp"
#include "ftc/sim/plant.hpp"

namespace ftc::sim {

struct ManipulatorParams {
  std::array<double, 2> masses{1.0, 1.0};                  // m1, m2 in kg
  std::array<double, 2> lengths{1.0, 1.0};                 // l1, l2 in m
  std::array<double, 2> centres_of_mass{0.5, 0.5};         // lc1, lc2 in m
  std::array<double, 2> inertias{1.0 / 12.0, 1.0 / 12.0};  // I1, I2 in kg·m² (uniform rods)
  double gravity = 9.81;                                   // g0 in m/s²
};

class Manipulator final : public Plant<2, 3> {
 public:
  using Mass = Mat<2, 2>;

  // Throws InputError naming each non-positive mass, length, centre-of-mass distance or inertia
  // and a negative gravity.
  explicit Manipulator(const ManipulatorParams& params = {});

  // Scratch space of one simulation for evaluating f and G at the nearby states of successive
  // RK4 stages (defined in sim_core; the simulator owns one).
  struct Workspace;

  Vector f(const State& x) const override;
  InputMatrix G(const State& x) const override;
  // The same f and G, from the sines and cosines kept in `ws` (equal to f(x), G(x) within an
  // ulp): what the simulator evaluates.
  Vector f(const State& x, Workspace& ws) const;
  InputMatrix G(const State& x, Workspace& ws) const;

  // G⁺ = B⁺ M(q): the Moore–Penrose right inverse of G without inverting GGᵀ.
  InputInverse G_pinv(const State& x) const override {
    return actuator_pinv() * mass_matrix(x.head<2>());
  }

  std::string model() const override { return "manipulator"; }

  // M(q) in kg·m².
  Mass mass_matrix(const Vector& q) const {
    const double c2 = math::cos(q[1]);
    Mass m;
    m << a1_ + 2.0 * a2_ * c2, a3_ + a2_ * c2,  //
        a3_ + a2_ * c2, a3_;
    return m;
  }
  // C(q, q̇) q̇ in N·m.
  Vector coriolis_torque(const Vector& q, const Vector& qd) const {
    const double h = a2_ * math::sin(q[1]);
    return Vector(-h * (2.0 * qd[0] * qd[1] + qd[1] * qd[1]), h * qd[0] * qd[0]);
  }
  // g(q) in N·m.
  Vector gravity_torque(const Vector& q) const {
    const double g2 = b2_ * math::cos(q[0] + q[1]);
    return Vector(b1_ * math::cos(q[0]) + g2, g2);
  }
  // Kinetic plus potential energy ½ q̇ᵀ M q̇ + V(q) in J (V = 0 with the arm horizontal).
  double energy(const State& x) const;

  const ManipulatorParams& params() const { return params_; }

  // B, joint torque per actuator torque (dimensionless).
  static InputMatrix actuator_matrix();
  // B⁺ = Bᵀ(BBᵀ)⁻¹ = [[2, −1], [−1, 2], [1, 1]] / 3.
  static InputInverse actuator_pinv();

 // The constants f and G are built from: a1, a2, a3, b1, b2 (below).
  std::array<double, 5> f_constants() const { return {a1_, a2_, a3_, b1_, b2_}; }

 private:
  ManipulatorParams params_;
  double a1_;  // m1 lc1² + m2 (l1² + lc2²) + I1 + I2: M11 less its cos q2 term, kg·m²
  double a2_;  // m2 l1 lc2, kg·m²
  double a3_;  // m2 lc2² + I2 = M22, kg·m²
  double b1_;  // (m1 lc1 + m2 l1) g0, N·m
  double b2_;  // m2 lc2 g0, N·m
};

}  // namespace ftc::sim
