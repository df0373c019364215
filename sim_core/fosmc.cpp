#include "ftc/sim/fosmc.hpp"

#include "checks.hpp"
#include "ftc/sim/plant_model.hpp"
#include "ftc/sim/sliding.hpp"

namespace ftc::sim {

Fosmc::Fosmc(const ControllerConfig& config, const Plant& plant, double sample_time)
    : config_(detail::checked_config(config, sample_time)),
      plant_(plant),
      fosm_(config_.c1, config_.c2, config_.alpha1, config_.alpha2),
      Ts_(sample_time) {}

Vec4 Fosmc::step(const Measurement& m) {
  const ControllerConfig& c = config_;
  const Vec3 fx = plant_.f(m);
  const Vec3 C = fosm_(m.X1, m.X2);
  const Vec3 sF = m.a + C;

  Vec3 v = fx + C;
  v += ur_;
  const Vec4 u = -plant_.G_pinv_times(m, v);

  ur_ += (Ts_ * c.switching_gain) * sigm(sF, c.theta);
  return u;
}

}  // namespace ftc::sim
