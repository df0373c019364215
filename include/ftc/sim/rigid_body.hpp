#pragma once
// A rigid body's attitude with the user's own inertia tensor and actuator geometry (SPEC §17):
// the plants `rigid_body` (reaction wheels or thrusters along any axes) and `multirotor` (any
// rotor layout, held in hover). n = 3; m actuators, 3 ≤ m ≤ 8 (compiled once for 8: the columns
// past m are zero and their commands stay 0; results and trajectories carry m).
//
// Rigid body (kinematics euler_321). X1 = (φ, θ, ψ) roll, pitch, yaw in rad, the 3-2-1 Euler
// angles of the body in an inertial frame (no orbital terms); X2 = Ẋ1 in rad/s. Body rates
// ω = W(X1) Ẋ1 with
//
//     W = [ 1    0      −sθ    ]      Ẇ Ẋ1 = ( −cθ θ̇ ψ̇,
//         [ 0    cφ    sφ cθ  ]                −sφ φ̇ θ̇ + (cφ cθ φ̇ − sφ sθ θ̇) ψ̇,
//         [ 0   −sφ    cφ cθ  ]                −cφ φ̇ θ̇ − (sφ cθ φ̇ + cφ sθ θ̇) ψ̇ )
//
// and Euler's equation J ω̇ = −ω × (J ω) + D u (J in kg·m², u in N·m) gives
//
//     f(X) = W⁻¹ ( J⁻¹ (−ω × J ω) − Ẇ Ẋ1 ),    G(X) = W⁻¹ J⁻¹ D,    G⁺ = D⁺ J W,
//
// D = [â_1 … â_m] the unit axes of the actuators (actuator j applies u_j â_j) and
// D⁺ = Dᵀ (D Dᵀ)⁻¹ (G⁺ = Gᵀ(GGᵀ)⁻¹ reduces to D⁺ J W for any invertible J and W). W is singular
// at θ = ±90°: a run in which |θ| passes 85° at a sample is flagged model_invalid.
//
// Multirotor (kinematics body_rates). X1 = (roll, pitch, yaw) in rad and X2 their rates, read
// as the body rates ω near hover (W = I), as for the hexarotor: f(X) = J⁻¹(−ω × J ω),
// G = J⁻¹ A, G⁺ = A⁺ J with A the torque per newton of each rotor's thrust, (y_i, −x_i, σ_i κ_i)
// for rotor i at (x_i, y_i) m (body frame, z up) spinning σ_i = +1 clockwise, −1 otherwise, with
// moment constant κ_i in m. The command is the thrust's deviation from the hover trim T_h (the
// minimum-norm thrusts with A T = 0, Σ T = m g), within [−T_h,i, T_max,i − T_h,i].
//
// With a diagonal J both compute f as (kx ω_y ω_z, ky ω_x ω_z, kz ω_x ω_y), kx = (Iy − Iz)/Ix, …,
// and G as A(k, j) / I_k, the hexarotor's operations: hexa_x with its numbers gives its bits.
#include <array>
#include <limits>
#include <string>

#include "ftc/sim/plant.hpp"

namespace ftc::sim {

inline constexpr int kMaxBodyActuators = 8;

enum class BodyKinematics : int { euler_321 = 1, body_rates = 0 };

struct RigidBodyParams {
  std::string model = "rigid_body";  // or "multirotor": the name the plant reports
  BodyKinematics kinematics = BodyKinematics::euler_321;
  // J, symmetric positive definite, kg·m² (row-major).
  std::array<double, 9> inertia{1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0};
  int actuators = 3;  // m
  // Column j of D (row-major 3×8): actuator j's torque per unit of its output (N·m per N·m for a
  // wheel, N·m per N for a rotor). Columns past m are zero.
  std::array<double, 3 * kMaxBodyActuators> torque{};
  // The operating point of each actuator (a rotor's hover thrust; 0 for a wheel) and the range
  // of its command about it, [lo, hi] (±inf: no limit).
  std::array<double, kMaxBodyActuators> u0{};
  std::array<double, kMaxBodyActuators> lo = filled(-std::numeric_limits<double>::infinity());
  std::array<double, kMaxBodyActuators> hi = filled(std::numeric_limits<double>::infinity());
  // D D⁺'s denominator in closed form, when D Dᵀ is diagonal and known exactly (the symmetric
  // rotor presets: diag(n l²/2, n l²/2, n κ²), as the hexarotor has always computed it); NaN:
  // D⁺ is computed from D.
  std::array<double, 3> closed_form_ddt{std::numeric_limits<double>::quiet_NaN(), 0.0, 0.0};
  // A multirotor's weight m g (N), which the rotors must be able to hold (recoverability).
  double weight = 0.0;
  // A multirotor's rotor range [0, T_max,i] in N.
  std::array<double, kMaxBodyActuators> max_thrust{};

  static std::array<double, kMaxBodyActuators> filled(double v) {
    std::array<double, kMaxBodyActuators> a;
    a.fill(v);
    return a;
  }
};

// The constants a pack's lanes read per lane (PackSetup's truth and model rows): flags, J, D,
// D⁺ and m, at these offsets.
struct RigidBodyConstants {
  static constexpr int kEuler = 0, kDiagonal = 1, kJ = 2, kD = 8, kDpinv = 32, kM = 56;
  static constexpr int kCount = 57;
};

class RigidBody final : public Plant<3, kMaxBodyActuators> {
 public:
  // Throws InputError naming what is wrong: /inertia (not symmetric, not positive definite,
  // saying which test failed), /actuators (fewer than 3 or more than 8, axes that do not span
  // R³), a limit that is not positive.
  explicit RigidBody(const RigidBodyParams& params);

  Vector f(const State& x) const override;
  InputMatrix G(const State& x) const override;
  bool input_matrix_is_constant() const override {
    return params_.kinematics == BodyKinematics::body_rates;
  }
  InputInverse G_pinv(const State& x) const override;
  std::string model() const override { return params_.model; }

  const RigidBodyParams& params() const { return params_; }
  int actuator_count() const { return params_.actuators; }
  // With Euler angles, whether a run left |θ| < 85° is reported (SimulationResult).
  bool reports_validity() const { return params_.kinematics == BodyKinematics::euler_321; }
  const std::array<double, RigidBodyConstants::kCount>& f_constants() const { return constants_; }

  struct Trim {
    std::array<double, kMaxBodyActuators> u0, lo, hi;
  };
  Trim actuator_trim() const { return {params_.u0, params_.lo, params_.hi}; }

  // For recoverability (PlantAdapter::recoverable), as the hexarotor's: each actuator's physical
  // range [floor, cap] and whether the actuators still acting can hold the operating point
  // strictly inside their ranges. A multirotor's is hover (zero torque and the weight); a rigid
  // body's is zero torque, which u = 0 gives unless an actuator is stuck: then the others must
  // cancel its torque within their limits (a wheel stuck at 0.2 N·m beside wheels of 0.1 N·m
  // that cannot is unrecoverable, whatever the rank of what is left).
  struct ThrustRange {
    std::array<double, kMaxBodyActuators> floor, cap;
  };
  ThrustRange thrust_range() const;
  bool trim_feasible(const std::array<bool, kMaxBodyActuators>& stuck,
                     const std::array<double, kMaxBodyActuators>& stuck_at,
                     const std::array<double, kMaxBodyActuators>& lost,
                     const ThrustRange& range) const;
  bool trim_feasible(const std::array<bool, kMaxBodyActuators>& stuck,
                     const std::array<double, kMaxBodyActuators>& stuck_at,
                     const std::array<double, kMaxBodyActuators>& lost) const {
    return trim_feasible(stuck, stuck_at, lost, thrust_range());
  }

  // D (3×8, columns past m zero) and D⁺ (8×3).
  const InputMatrix& torque_matrix() const { return D_; }
  const InputInverse& torque_inverse() const { return Dp_; }

 private:
  struct Terms;
  Terms terms(const State& x) const;
  std::array<double, RigidBodyConstants::kCount> constants() const;  // f_constants(), formed once

  RigidBodyParams params_;
  bool diagonal_ = false;
  InputMatrix D_;
  InputInverse Dp_;
  std::array<double, RigidBodyConstants::kCount> constants_{};
};

}  // namespace ftc::sim
