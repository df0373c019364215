#pragma once
// Adaptive neural PI full-order sliding-mode controller (paper eqs. 20, 22, 26–30; SPEC §5).
// Model-free: f(X) and the fault/disturbance bound are replaced by an integral RBF network Ω
// and an adaptive switching gain K̂a.
//
//   ψ_j  = exp(-‖X - μ_j‖² / σ²),  j = 1..l,  X ∈ R^2n, μ_j = c_j (1,…,1), c_j evenly on
//   centre_range sF   = a + C(X),   sPI = Kp sF + Ki I u_d  = -G⁺ (Ω + C(X) + (Ki/Kp) I + ur) I +=
//   Ts · sF ur  += Ts · (K̂a + ζ) ⊙ sigm(sPI) K̂a  += Ts · |sPI| / λ               (per axis, K̂a(0) =
//   ka0) Ω   += Ts · Wᵀ ψ                     (W is l×n, the weights θ̂) W   += Ts · weight_rate · ψ
//   sPIᵀ     (weight_rate = 1/α of eq. 30)
//
// Units (spacecraft): Ω, ur rad/s²; K̂a, ζ rad/s³; λ and weight_rate set the adaptation speeds.
// The state is updated in the order above, each from the values of sample k (forward Euler).
#include <Eigen/Core>
#include <cmath>

#include "checks.hpp"
#include "controllers/plant_model.hpp"
#include "controllers/sliding.hpp"
#include "ftc/sim/controller.hpp"
#include "lanes/elementary.hpp"

namespace ftc::sim {

template <int N, int M>
class AdaptiveNeuralPiFosmc final : public Controller<N, M> {
 public:
  static constexpr int kMaxNodes = 64;
  using Weights = Eigen::Matrix<double, Eigen::Dynamic, N, 0, kMaxNodes, N>;
  using Activations = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, kMaxNodes, 1>;

  AdaptiveNeuralPiFosmc(const ControllerConfig& config, const Plant<N, M>& plant,
                        double sample_time)
      : config_(detail::checked_config(config, sample_time)),
        plant_(plant),
        fosm_(config_.c1, config_.c2, config_.alpha1, config_.alpha2),
        Ts_(sample_time),
        l_(static_cast<int>(config_.nodes)) {
    centres_.resize(l_);
    const double lo = config_.centre_range[0], hi = config_.centre_range[1];
    for (int j = 0; j < l_; ++j)
      centres_[j] = l_ == 1 ? 0.5 * (lo + hi) : lo + (hi - lo) * j / (l_ - 1);
    W_.resize(l_, N);
    reset();
  }

  void reset() override {
    I_.setZero();
    ur_.setZero();
    Ka_.setConstant(config_.ka0);
    Omega_.setZero();
    W_.setZero();
  }

  using Controller<N, M>::step;
  Vec<M> step(const Measurement<N>& m) override {
    const ControllerConfig& c = config_;
    const StateOf<N> x = (StateOf<N>() << m.X1, m.X2).finished();
    const Vec<N> C = fosm_(m.X1, m.X2);
    const Vec<N> sF = m.a + C;
    Vec<N> sPI = c.Kp * sF;
    sPI += c.Ki * I_;

    Vec<N> v = Omega_ + C;
    v += (c.Ki / c.Kp) * I_;
    v += ur_;
    const Vec<M> u = -plant_.G_pinv_times(m, v);

    // ψ_j with μ_j = c_j (1,…,1); Activations has a fixed capacity, so this does not allocate.
    const double inv_w2 = 1.0 / (c.width * c.width);
    Activations psi(l_);
    for (int j = 0; j < l_; ++j) {
      const double d2 = (x.array() - centres_[j]).square().sum();
      psi[j] = lane::exp(-d2 * inv_w2);
    }

    I_ += Ts_ * sF;
    ur_ += Ts_ * (Ka_.array() + c.zeta).matrix().cwiseProduct(sigm(sPI, c.theta));
    Ka_ += (Ts_ / c.lambda) * sPI.cwiseAbs();
    Vec<N> net = Vec<N>::Zero();
    for (int j = 0; j < l_; ++j) net += psi[j] * W_.row(j).transpose();
    Omega_ += Ts_ * net;
    const double rate = Ts_ * c.weight_rate;
    for (int j = 0; j < l_; ++j) W_.row(j) += (rate * psi[j]) * sPI.transpose();
    return u;
  }
  const ControllerConfig& config() const override { return config_; }
  double sample_time() const override { return Ts_; }

  const Vec<N>& adaptive_gain() const { return Ka_; }
  const Vec<N>& network_output() const { return Omega_; }

 private:
  ControllerConfig config_;
  detail::PlantModel<N, M> plant_;
  FosmTerm fosm_;  // C(X)
  double Ts_;
  int l_;
  Activations centres_;  // c_j
  Vec<N> I_, ur_, Ka_, Omega_;
  Weights W_;  // fixed capacity, no heap
};

}  // namespace ftc::sim
