#include "ftc/sim/pi_fosmc.hpp"

#include "checks.hpp"
#include "ftc/sim/plant_model.hpp"
#include "ftc/sim/sliding.hpp"

namespace ftc::sim {

PiFosmc::PiFosmc(const ControllerConfig& config, const Plant& plant, double sample_time)
    : config_(detail::checked_config(config, sample_time)),
      plant_(plant),
      fosm_(config_.c1, config_.c2, config_.alpha1, config_.alpha2),
      Ts_(sample_time) {}

// The operations are ordered as in Fosmc::step so that Kp = 1, Ki = 0 reproduces FOSMC bit for
// bit (x + 0·I = x and 1·sF = sF are exact in IEEE arithmetic).
Vec4 PiFosmc::step(const Measurement& m) {
  const ControllerConfig& c = config_;
  const Vec3 fx = plant_.f(m);
  const Vec3 C = fosm_(m.X1, m.X2);
  const Vec3 sF = m.a + C;
  Vec3 sPI = c.Kp * sF;
  sPI += c.Ki * I_;

  Vec3 v = fx + C;
  v += (c.Ki / c.Kp) * I_;
  v += ur_;
  const Vec4 u = -plant_.G_pinv_times(m, v);

  I_ += Ts_ * sF;
  ur_ += (Ts_ * c.switching_gain) * sigm(sPI, c.theta);
  return u;
}

}  // namespace ftc::sim
