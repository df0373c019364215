#pragma once
// Fixed-size vector and matrix types of the simulation core.
//
// A plant fixes its shape at compile time: n axes (X1, X2 in R^n) and m actuators (u in R^m).
// The core is written once over these two numbers, and every quantity in the hot loop is a
// fixed-size Eigen object: no heap allocation, and the compiler unrolls the small loops.
#include <Eigen/Core>

// Marks the small functions of the simulation's hot loop. The loop is compiled once per plant and
// controller class, and in such a large function GCC's inliner stops at its growth limits before
// reaching these; left as calls they cost about a sixth of a simulation.
#if defined(__GNUC__)
#define FTC_HOT_INLINE [[gnu::always_inline]] inline
#define FTC_HOT_LAMBDA __attribute__((always_inline))
#else
#define FTC_HOT_INLINE inline
#define FTC_HOT_LAMBDA
#endif

namespace ftc::sim {

template <int N>
using Vec = Eigen::Matrix<double, N, 1>;
template <int N>
using StateOf = Eigen::Matrix<double, 2 * N, 1>;  // X = (X1, X2): positions, rates
template <int R, int C>
using Mat = Eigen::Matrix<double, R, C>;

// The spacecraft's shapes (n = 3 attitude axes, m = 4 actuators), named for readability where
// code is about it.
using Vec3 = Vec<3>;
using Vec4 = Vec<4>;
using State = StateOf<3>;
using Mat34 = Mat<3, 4>;
using Mat43 = Mat<4, 3>;

// Sizes a file may name (axis and actuator indices are validated against the plant's own n, m).
inline constexpr int kMaxAxes = 8;
inline constexpr int kMaxActuators = 16;

}  // namespace ftc::sim
