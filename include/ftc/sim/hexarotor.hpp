#pragma once
// A hexarotor's attitude (n = 3, m = 6): six rotors in the standard hexagonal layout, held in
// hover. Only the rotation is modelled; the altitude is assumed held by the collective thrust.
//
// X1 = (roll φ, pitch θ, yaw ψ) in rad, X2 their rates in rad/s, read as the body rates
// (p, q, r) (near hover the Euler rates and the body rates agree to first order). Euler's
// equations for a rigid body with principal inertias Ix, Iy, Iz (kg·m²):
//
//   dp/dt = (Iy − Iz)/Ix q r + τx/Ix,   dq/dt = (Iz − Ix)/Iy p r + τy/Iy,
//   dr/dt = (Ix − Iy)/Iz p q + τz/Iz
//
// so f(X) = (kx x5 x6, ky x4 x6, kz x4 x5) with kx = (Iy − Iz)/Ix, ... (rad/s²), and G = J⁻¹ A.
//
// Rotor i (1..6) sits at arm length l at the angle α_i = 30° + 60°·(i − 1) from the body x axis,
// counter-clockwise seen from above (z up), and spins clockwise for odd i, counter-clockwise for
// even i. Its thrust T_i (N, along +z) gives the roll and pitch torques of the arm,
// τx = l sin α_i T_i and τy = −l cos α_i T_i, and its drag the yaw torque τz = σ_i κ T_i, with
// σ_i = +1 for a clockwise rotor and −1 otherwise and κ the moment constant (m: N·m of drag
// torque per N of thrust). A is the 3×6 matrix of these torques per newton.
//
// The command u_i is the deviation of rotor i's thrust from hover, T_i = T_h + u_i with
// T_h = m g / 6, so u = 0 holds the hexarotor level; the rotor's thrust lies in [0, T_max], so
// u_i ∈ [−T_h, T_max − T_h], limits that are not symmetric (actuator_trim()). Faults act on
// the rotor's thrust, after it is held within [0, T_max] (SPEC §17.1's order: limits, faults,
// limits): a loss of effectiveness ρ gives (1 − ρ)(T_h + u_i), so a rotor at 50 % loss gives at
// most T_max / 2 however hard it is commanded, and a rotor that has failed (ρ = 1) gives no
// thrust at all, u_i = −T_h, and loses its share of the hover thrust too; a stuck rotor holds the
// thrust `value` (N, within [0, T_max]); a bias adds to the thrust. A loss on a rotor also
// unbalances the yaw torque, as every rotor's thrust carries its drag torque σ_i κ T_i.
//
// G⁺: for this layout A Aᵀ = diag(3 l², 3 l², 6 κ²), so G⁺ = Gᵀ(GGᵀ)⁻¹ = A⁺ J with
// A⁺ = Aᵀ diag(1/(3 l²), 1/(3 l²), 1/(6 κ²)): no matrix is inverted.
//
// Default parameters: the Yuneec Typhoon H480 as PX4's simulator models it (docs/model.md, "A
// third plant").
#include <array>
#include <string>

#include "ftc/sim/plant.hpp"

namespace ftc::sim {

struct HexarotorParams {
  std::array<double, 3> inertia{0.011, 0.015, 0.021};  // Ix, Iy, Iz in kg·m²
  double mass = 2.02;                                 // kg
  double arm_length = 0.243;                          // l in m
  double max_thrust = 19.2343;                        // T_max per rotor in N
  double moment_constant = 0.06;                      // κ in m
  double gravity = 9.81;                              // g in m/s²
};

class Hexarotor final : public Plant<3, 6> {
 public:
  // Throws InputError naming a non-positive parameter, or /max_thrust when six rotors at full
  // thrust cannot carry the weight.
  explicit Hexarotor(const HexarotorParams& params = {});

  Vector f(const State& x) const override;
  InputMatrix G(const State&) const override { return G_; }
  bool input_matrix_is_constant() const override { return true; }
  InputInverse G_pinv(const State&) const override { return G_pinv_; }
  std::string model() const override { return "hexarotor"; }

  const HexarotorParams& params() const { return params_; }
  // The constants f and G are built from: Ix, Iy, Iz, l, κ.
  std::array<double, 5> f_constants() const;
  // T_h = m g / 6, in N.
  double hover_thrust() const { return hover_; }

  // Each rotor's hover thrust u0 = T_h and the limits of its command, [−T_h, T_max − T_h].
  struct Trim {
    std::array<double, 6> u0, lo, hi;
  };
  Trim actuator_trim() const;

  // The thrust each rotor can give, in N: [floor_i, cap_i], by default [0, T_max]; a scenario's
  // saturation narrows it to T_h ± its limit.
  struct ThrustRange {
    std::array<double, 6> floor, cap;
  };
  ThrustRange thrust_range() const;

  // Whether the rotors can still hold hover with zero torque (Σ T_i = m g, A T = 0) with every
  // rotor that still acts strictly inside its range [floor_i, (1 − lost_i) cap_i], the stuck
  // ones at their thrust (within their range) and the failed ones (lost_i ≥ 1) at zero: only then
  // can the controller push every axis both ways. Found by maximising the smallest margin to a
  // limit (a linear program, solved over the vertices of the few free directions).
  bool trim_feasible(const std::array<bool, 6>& stuck, const std::array<double, 6>& stuck_at,
                     const std::array<double, 6>& lost, const ThrustRange& range) const;
  bool trim_feasible(const std::array<bool, 6>& stuck, const std::array<double, 6>& stuck_at,
                     const std::array<double, 6>& lost) const {
    return trim_feasible(stuck, stuck_at, lost, thrust_range());
  }
  // The smallest margin of that program in N (negative or zero when infeasible).
  double trim_margin(const std::array<bool, 6>& stuck, const std::array<double, 6>& stuck_at,
                     const std::array<double, 6>& lost, const ThrustRange& range) const;
  double trim_margin(const std::array<bool, 6>& stuck, const std::array<double, 6>& stuck_at,
                     const std::array<double, 6>& lost) const {
    return trim_margin(stuck, stuck_at, lost, thrust_range());
  }

  // A: torque (N·m) per newton of each rotor's thrust.
  InputMatrix torque_matrix() const;

 private:
  HexarotorParams params_;
  double kx_, ky_, kz_;
  double hover_;
  InputMatrix G_;
  InputInverse G_pinv_;
};

}  // namespace ftc::sim
