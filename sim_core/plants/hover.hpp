#pragma once
// Whether the actuators still acting can hold the operating point: hover for rotors, zero torque
// against a stuck wheel for a rigid body. One linear program for every layout (the hexarotor,
// the multirotor and the rigid body share it). Private to sim_core.
#include <Eigen/Core>
#include <span>

namespace ftc::sim::detail {

// The largest margin t such that the actuators still acting hold zero torque, A T = 0, and, when
// `weight` > 0, the weight, Σ T = weight, each acting actuator i strictly within
// lo_i + t ≤ T_i ≤ hi_i − t. A loss ρ_i (`lost`) scales what actuator i delivers and the limits
// apply again: [lo_i, hi_i] = [floor_i, cap_i] ∩ (1 − ρ_i)·[floor_i, cap_i]. A stuck actuator gives
// its value (within its range), a failed one (ρ ≥ 1) nothing. A bound may be infinite (no
// limit); +inf when no acting actuator is limited and the equations can be solved, −inf when
// they cannot. `scale` sets the tolerances (the largest finite limit). A: 3 × k, the torque per
// unit output of each of the k actuators.
double hold_margin(const Eigen::Ref<const Eigen::MatrixXd>& A, double weight,
                   std::span<const bool> stuck, std::span<const double> stuck_at,
                   std::span<const double> lost, std::span<const double> floor,
                   std::span<const double> cap, double scale);

}  // namespace ftc::sim::detail
