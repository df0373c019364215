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
      pq_(config_.p / config_.q) {}

Vec4 Nftsmc::step(const Measurement& m) {
  const ControllerConfig& c = config_;
  const Vec3 fx = plant_.f(m);

  Vec3 s = m.X1 + c.sigma1 * sig(m.X1, c.alpha);
  s += c.sigma2 * sig(m.X2, pq_);

  const double k = (c.q / c.p) / c.sigma2;
  Vec3 ueq = fx;
  for (int i = 0; i < kAxes; ++i) {
    const double ax = std::abs(m.X1[i]);
    // |X1|^(α-1) with α > p/q > 1, so 0^(α-1) = 0: no singularity at X1 = 0.
    const double gain = 1.0 + c.alpha * c.sigma1 * std::pow(ax, c.alpha - 1.0);
    ueq[i] += k * gain * sig(m.X2[i], 2.0 - pq_);
  }
  Vec3 v = ueq + c.switching_gain * sigm(s, c.theta);
  return -plant_.G_pinv_times(m, v);
}

}  // namespace ftc::sim
