#pragma once
// Fixed-size vector and matrix types of the simulation core.
//
// v1 fixes the plant shape at n = 3 axes and m = 4 actuators (the spacecraft of the paper) so
// that every quantity in the hot loop is a fixed-size Eigen object: no heap allocation, and the
// compiler unrolls the small loops. A plant of the same shape plugs in through ftc::sim::Plant.
#include <Eigen/Core>

namespace ftc::sim {

inline constexpr int kAxes = 3;       // n: attitude axes (roll, pitch, yaw)
inline constexpr int kActuators = 4;  // m: reaction actuators
inline constexpr int kStates = 2 * kAxes;

using Vec3 = Eigen::Matrix<double, kAxes, 1>;
using Vec4 = Eigen::Matrix<double, kActuators, 1>;
using State = Eigen::Matrix<double, kStates, 1>;  // X = (X1, X2): angles (rad), rates (rad/s)
using Mat34 = Eigen::Matrix<double, kAxes, kActuators>;
using Mat43 = Eigen::Matrix<double, kActuators, kAxes>;

}  // namespace ftc::sim
