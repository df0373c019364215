#include "ftc/sim/nftsmc.hpp"

#include <cmath>

#include "checks.hpp"
#include "ftc/sim/plant_model.hpp"
#include "ftc/sim/sliding.hpp"

namespace ftc::sim {

Nftsmc::Nftsmc(const ControllerConfig& config, const Plant& plant, double sample_time)
    : config_(detail::checked_config(config, sample_time)),
      plant_(plant),
      Ts_(sample_time),
      pq_(config_.p / config_.q),
      pow_alpha_(config_.alpha),
      pow_pq_(pq_),
      pow_rate_(2.0 - pq_),
      pow_gain_(config_.alpha - 1.0) {}

Vec4 Nftsmc::step(const Measurement& m) {
  const ControllerConfig& c = config_;
  const Vec3 fx = plant_.f(m);

  Vec3 s = m.X1 + c.sigma1 * sig(m.X1, pow_alpha_);
  s += c.sigma2 * sig(m.X2, pow_pq_);

  const double k = (c.q / c.p) / c.sigma2;
  Vec3 ueq = fx;
  for (int i = 0; i < kAxes; ++i) {
    // |X1|^(α-1) with α > p/q > 1, so 0^(α-1) = 0: no singularity at X1 = 0.
    const double gain = 1.0 + c.alpha * c.sigma1 * pow_gain_(std::abs(m.X1[i]));
    ueq[i] += k * gain * pow_rate_(m.X2[i]);
  }
  Vec3 v = ueq + c.switching_gain * sigm(s, c.theta);
  return -plant_.G_pinv_times(m, v);
}

}  // namespace ftc::sim
