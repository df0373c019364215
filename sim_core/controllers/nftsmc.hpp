#pragma once
// Nonsingular fast terminal sliding-mode controller (paper Appendix C, corrected as in SPEC §5).
//
//   s    = X1 + σ1 sig^α(X1) + σ2 sig^{p/q}(X2)
//   ueq  = f(X) + (q/p) σ2⁻¹ (1 + α σ1 |X1|^{α-1}) ⊙ sig^{2-p/q}(X2)
//   u_d  = -G⁺ (ueq + K sigm(s))
//
// Units (spacecraft): X1 rad, X2 rad/s, ueq and K rad/s². p, q positive odd integers with
// 1 < p/q < 2 and α > p/q. Memoryless: reset() has nothing to clear. Model-based (uses f, G⁺).
#include <cmath>

#include "checks.hpp"
#include "controllers/plant_model.hpp"
#include "controllers/sliding.hpp"
#include "ftc/sim/controller.hpp"

namespace ftc::sim {

template <int N, int M>
class Nftsmc final : public Controller<N, M> {
 public:
  Nftsmc(const ControllerConfig& config, const Plant<N, M>& plant, double sample_time)
      : config_(detail::checked_config(config, sample_time)),
        plant_(plant),
        Ts_(sample_time),
        pq_(config_.p / config_.q),
        pow_alpha_(config_.alpha),
        pow_pq_(pq_),
        pow_rate_(2.0 - pq_),
        pow_gain_(config_.alpha - 1.0) {}

  void reset() override {}
  using Controller<N, M>::step;
  Vec<M> step(const Measurement<N>& m) override {
    const ControllerConfig& c = config_;
    const Vec<N> fx = plant_.f(m);

    Vec<N> s = m.X1 + c.sigma1 * sig(m.X1, pow_alpha_);
    s += c.sigma2 * sig(m.X2, pow_pq_);

    const double k = (c.q / c.p) / c.sigma2;
    Vec<N> ueq = fx;
    for (int i = 0; i < N; ++i) {
      // |X1|^(α-1) with α > p/q > 1, so 0^(α-1) = 0: no singularity at X1 = 0.
      const double gain = 1.0 + c.alpha * c.sigma1 * pow_gain_(std::abs(m.X1[i]));
      ueq[i] += k * gain * pow_rate_(m.X2[i]);
    }
    Vec<N> v = ueq + c.switching_gain * sigm(s, c.theta);
    return -plant_.G_pinv_times(m, v);
  }
  const ControllerConfig& config() const override { return config_; }
  double sample_time() const override { return Ts_; }

 private:
  ControllerConfig config_;
  detail::PlantModel<N, M> plant_;
  double Ts_;
  double pq_;  // p/q
  // sig^α, sig^{p/q}, sig^{2-p/q} and |·|^{α-1}
  SigPower pow_alpha_, pow_pq_, pow_rate_, pow_gain_;
};

}  // namespace ftc::sim
