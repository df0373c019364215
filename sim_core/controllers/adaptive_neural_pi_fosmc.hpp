#pragma once
// Adaptive neural PI full-order sliding-mode controller (paper eqs. 20, 22, 26–30; SPEC §5).
// Model-free: f(X) and the fault/disturbance bound are replaced by an integral RBF network Ω
// and an adaptive switching gain K̂a.
//
//   ψ_j  = exp(-‖X - μ_j‖² / σ²),  j = 1..l,  X ∈ R^2n,  μ_j = c_j (1,…,1), c_j evenly on
//          centre_range
//   sF   = a + C(X),   sPI = Kp sF + Ki I
//   u_d  = -G⁺ (Ω + C(X) + (Ki/Kp) I + ur)
//   I   += Ts · sF
//   ur  += Ts · (K̂a + ζ) ⊙ sigm(sPI)
//   K̂a  += Ts · |sPI| / λ               (per axis, K̂a(0) = ka0)
//   Ω   += Ts · Wᵀ ψ                     (W is l×n, the weights θ̂)
//   W   += Ts · weight_rate · ψ sPIᵀ     (weight_rate = 1/α of eq. 30)
//
// Units (spacecraft): Ω, ur rad/s²; K̂a, ζ rad/s³; λ and weight_rate set the adaptation speeds.
// The state is updated in the order above, each from the values of sample k (forward Euler).
// The law itself is law::AdaptiveNeuralPiFosmc (controllers/laws.hpp), shared with the batch
// simulator; at most 64 nodes.
#include "checks.hpp"
#include "controllers/laws.hpp"
#include "controllers/plant_model.hpp"

namespace ftc::sim {

template <int N, int M>
class AdaptiveNeuralPiFosmc final
    : public detail::LawController<N, M, law::AdaptiveNeuralPiFosmc, false> {
  using Base = detail::LawController<N, M, law::AdaptiveNeuralPiFosmc, false>;

 public:
  using Base::Base;
  Vec<N> adaptive_gain() const {
    return Eigen::Map<const Vec<N>>(this->law().adaptive_gain().data());
  }
  Vec<N> network_output() const {
    return Eigen::Map<const Vec<N>>(this->law().network_output().data());
  }
};

namespace detail {
template <>
struct ControllerClass<ControllerType::adaptive_neural_pi_fosmc> {
  template <int N, int M>
  using type = AdaptiveNeuralPiFosmc<N, M>;
};
}  // namespace detail

}  // namespace ftc::sim
