#pragma once
// The plant concept of the paper (eq. 1): a second-order system
//
//     dX1/dt = X2
//     dX2/dt = f(X) + G(X) u + Δ(t)
//
// with X1, X2 in R^n and u in R^m the applied actuator outputs. A plant owns its dimensions,
// its drift term f and its input (allocation) matrix G; the controllers, faults, metrics and
// the simulator are written once over (n, m) and see a plant only through this interface.
//
// To add a plant: derive a final class from Plant<n, m> (see spacecraft.hpp and
// manipulator.hpp), describe its parameters and register it in sim_core/plants/registry.cpp.
#include <Eigen/LU>
#include <string>

#include "ftc/sim/types.hpp"

namespace ftc::sim {

template <int N, int M>
class Plant {
 public:
  static constexpr int kAxes = N;
  static constexpr int kActuators = M;
  static constexpr int kStates = 2 * N;
  using Vector = Vec<N>;
  using Input = Vec<M>;
  using State = StateOf<N>;
  using InputMatrix = Mat<N, M>;
  using InputInverse = Mat<M, N>;

  virtual ~Plant() = default;

  // Drift term f(X), in units of X2 per second.
  virtual Vector f(const State& x) const = 0;
  // Input matrix G(X): acceleration per unit of actuator output.
  virtual InputMatrix G(const State& x) const = 0;
  // True when G does not depend on X; the simulator and controllers then read it once per run.
  virtual bool input_matrix_is_constant() const { return false; }
  // Moore–Penrose right inverse G⁺ = Gᵀ(GGᵀ)⁻¹, so that G G⁺ = I_n.
  virtual InputInverse G_pinv(const State& x) const { return right_inverse(G(x)); }

  virtual std::string model() const = 0;

  static InputInverse right_inverse(const InputMatrix& G) {
    const Mat<N, N> GGt = G * G.transpose();
    return G.transpose() * GGt.inverse();
  }
};

}  // namespace ftc::sim
