#pragma once
// Nonsingular fast terminal sliding-mode controller (paper Appendix C, corrected as in SPEC §5).
//
//   s    = X1 + σ1 sig^α(X1) + σ2 sig^{p/q}(X2)
//   ueq  = f(X) + (q/p) σ2⁻¹ (1 + α σ1 |X1|^{α-1}) ⊙ sig^{2-p/q}(X2)
//   u_d  = -G⁺ (ueq + K sigm(s))
//
// Units: X1 rad, X2 rad/s, ueq and K rad/s². p, q positive odd integers with 1 < p/q < 2 and
// α > p/q. Memoryless: reset() has nothing to clear. Model-based (uses f and G⁺).
#include "ftc/sim/controller.hpp"
#include "ftc/sim/plant_model.hpp"
#include "ftc/sim/sig_power.hpp"

namespace ftc::sim {

class Nftsmc final : public Controller {
 public:
  Nftsmc(const ControllerConfig& config, const Plant& plant, double sample_time);

  void reset() override {}
  Vec4 step(const Measurement& m) override;
  using Controller::step;
  const ControllerConfig& config() const override { return config_; }
  double sample_time() const override { return Ts_; }

 private:
  ControllerConfig config_;
  detail::PlantModel plant_;
  double Ts_;
  double pq_;  // p/q
  // sig^α, sig^{p/q}, sig^{2-p/q} and |·|^{α-1}
  SigPower pow_alpha_, pow_pq_, pow_rate_, pow_gain_;
};

}  // namespace ftc::sim
