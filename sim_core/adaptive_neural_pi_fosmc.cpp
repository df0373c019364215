#include "ftc/sim/adaptive_neural_pi_fosmc.hpp"

#include <cmath>

#include "checks.hpp"
#include "ftc/sim/plant_model.hpp"
#include "ftc/sim/sliding.hpp"

namespace ftc::sim {

AdaptiveNeuralPiFosmc::AdaptiveNeuralPiFosmc(const ControllerConfig& config, const Plant& plant,
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
  W_.resize(l_, kAxes);
  reset();
}

void AdaptiveNeuralPiFosmc::reset() {
  I_.setZero();
  ur_.setZero();
  Ka_.setConstant(config_.ka0);
  Omega_.setZero();
  W_.setZero();
}

Vec4 AdaptiveNeuralPiFosmc::step(const Measurement& m) {
  const ControllerConfig& c = config_;
  const State x = (State() << m.X1, m.X2).finished();
  const Vec3 C = fosm_(m.X1, m.X2);
  const Vec3 sF = m.a + C;
  Vec3 sPI = c.Kp * sF;
  sPI += c.Ki * I_;

  Vec3 v = Omega_ + C;
  v += (c.Ki / c.Kp) * I_;
  v += ur_;
  const Vec4 u = -plant_.G_pinv_times(m, v);

  // ψ_j with μ_j = c_j (1,…,1); Activations has a fixed capacity, so this does not allocate.
  const double inv_w2 = 1.0 / (c.width * c.width);
  Activations psi(l_);
  for (int j = 0; j < l_; ++j) {
    const double d2 = (x.array() - centres_[j]).square().sum();
    psi[j] = std::exp(-d2 * inv_w2);
  }

  I_ += Ts_ * sF;
  ur_ += Ts_ * (Ka_.array() + c.zeta).matrix().cwiseProduct(sigm(sPI, c.theta));
  Ka_ += (Ts_ / c.lambda) * sPI.cwiseAbs();
  Vec3 net = Vec3::Zero();
  for (int j = 0; j < l_; ++j) net += psi[j] * W_.row(j).transpose();
  Omega_ += Ts_ * net;
  const double rate = Ts_ * c.weight_rate;
  for (int j = 0; j < l_; ++j) W_.row(j) += (rate * psi[j]) * sPI.transpose();
  return u;
}

}  // namespace ftc::sim
