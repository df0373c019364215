#pragma once
// Whether rotors can still hold hover: the linear program of Hexarotor::trim_margin, for any
// layout (the hexarotor and the multirotor share it). Private to sim_core.
#include <Eigen/Core>
#include <span>

namespace ftc::sim::detail {

// The largest margin t (N) such that the rotors still acting hold zero torque and the weight,
// A T = 0 and Σ T = weight, each acting rotor i strictly within floor_i + t ≤ T_i ≤ cap_i − t
// with cap_i = max(floor_i, (1 − lost_i) cap_i); a stuck rotor gives its thrust (within its
// range), a failed one (lost ≥ 1) none. −inf when no thrusts solve the equations. `scale` sets
// the tolerances (the largest thrust). A: 3 × k, the torque per newton of each of the k rotors.
double hover_margin(const Eigen::Ref<const Eigen::MatrixXd>& A, double weight,
                    std::span<const bool> stuck, std::span<const double> stuck_at,
                    std::span<const double> lost, std::span<const double> floor,
                    std::span<const double> cap, double scale);

}  // namespace ftc::sim::detail
