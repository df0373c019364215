#pragma once
// Adaptive neural PI full-order sliding-mode controller (paper eqs. 20, 22, 26–30; SPEC §5).
// Model-free: f(X) and the fault/disturbance bound are replaced by an integral RBF network Ω
// and an adaptive switching gain K̂a.
//
//   ψ_j  = exp(-‖X - μ_j‖² / σ²),  j = 1..l,  X ∈ R⁶, μ_j = c_j (1,…,1), c_j evenly on centre_range
//   sF   = a + C(X),   sPI = Kp sF + Ki I
//   u_d  = -G⁺ (Ω + C(X) + (Ki/Kp) I + ur)
//   I   += Ts · sF
//   ur  += Ts · (K̂a + ζ) ⊙ sigm(sPI)
//   K̂a  += Ts · |sPI| / λ               (per axis, K̂a(0) = ka0)
//   Ω   += Ts · Wᵀ ψ                     (W is l×3, the weights θ̂)
//   W   += Ts · weight_rate · ψ sPIᵀ     (weight_rate = 1/α of eq. 30)
//
// Units: Ω, ur rad/s²; K̂a, ζ rad/s³; λ and weight_rate set the adaptation speeds.
// The state is updated in the order above, each from the values of sample k (forward Euler).
#include <Eigen/Core>

#include "ftc/sim/controller.hpp"
#include "ftc/sim/plant_model.hpp"
#include "ftc/sim/sliding.hpp"

namespace ftc::sim {

class AdaptiveNeuralPiFosmc final : public Controller {
 public:
  static constexpr int kMaxNodes = 64;
  using Weights = Eigen::Matrix<double, Eigen::Dynamic, kAxes, 0, kMaxNodes, kAxes>;
  using Activations = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, kMaxNodes, 1>;

  AdaptiveNeuralPiFosmc(const ControllerConfig& config, const Plant& plant, double sample_time);

  void reset() override;
  Vec4 step(const Measurement& m) override;
  using Controller::step;
  const ControllerConfig& config() const override { return config_; }
  double sample_time() const override { return Ts_; }

  const Vec3& adaptive_gain() const { return Ka_; }
  const Vec3& network_output() const { return Omega_; }

 private:
  ControllerConfig config_;
  detail::PlantModel plant_;
  FosmTerm fosm_;  // C(X)
  double Ts_;
  int l_;
  Activations centres_;  // c_j
  Vec3 I_, ur_, Ka_, Omega_;
  Weights W_;  // fixed capacity, no heap
};

}  // namespace ftc::sim
