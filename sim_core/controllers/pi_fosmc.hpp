#pragma once
// PI full-order sliding-mode controller (paper eqs. 7, 11–13; SPEC §5).
//
//   sF   = a + C(X)                     full-order surface (eq. 8)
//   sPI  = Kp sF + Ki I,   I = ∫ sF dt  PI surface (eq. 7)
//   u_d  = -G⁺ (f(X) + C(X) + (Ki/Kp) I + ur)     (eq. 11 with eq. 12 divided through by Kp)
//   I   += Ts · sF
//   ur  += Ts · K · sigm(sPI)           (eq. 13 with the sigmoid for sign)
//
// Units (spacecraft): sF rad/s², I rad/s, ur rad/s², K = Π+ζ rad/s³, Kp dimensionless, Ki 1/s.
// With Kp = 1, Ki = 0 it issues exactly the commands of FOSMC. Model-based.
#include "checks.hpp"
#include "controllers/plant_model.hpp"
#include "controllers/sliding.hpp"
#include "ftc/sim/controller.hpp"

namespace ftc::sim {

template <int N, int M>
class PiFosmc final : public Controller<N, M> {
 public:
  PiFosmc(const ControllerConfig& config, const Plant<N, M>& plant, double sample_time)
      : config_(detail::checked_config(config, sample_time)),
        plant_(plant),
        fosm_(config_.c1, config_.c2, config_.alpha1, config_.alpha2),
        Ts_(sample_time) {}

  void reset() override {
    I_.setZero();
    ur_.setZero();
  }
  using Controller<N, M>::step;
  // The operations are ordered as in Fosmc::step so that Kp = 1, Ki = 0 reproduces FOSMC bit
  // for bit (x + 0·I = x and 1·sF = sF are exact in IEEE arithmetic).
  Vec<M> step(const Measurement<N>& m) override {
    const ControllerConfig& c = config_;
    const Vec<N> fx = plant_.f(m);
    const Vec<N> C = fosm_(m.X1, m.X2);
    const Vec<N> sF = m.a + C;
    Vec<N> sPI = c.Kp * sF;
    sPI += c.Ki * I_;

    Vec<N> v = fx + C;
    v += (c.Ki / c.Kp) * I_;
    v += ur_;
    const Vec<M> u = -plant_.G_pinv_times(m, v);

    I_ += Ts_ * sF;
    ur_ += (Ts_ * c.switching_gain) * sigm(sPI, c.theta);
    return u;
  }
  const ControllerConfig& config() const override { return config_; }
  double sample_time() const override { return Ts_; }

 private:
  ControllerConfig config_;
  detail::PlantModel<N, M> plant_;
  FosmTerm fosm_;  // C(X)
  double Ts_;
  Vec<N> I_ = Vec<N>::Zero();
  Vec<N> ur_ = Vec<N>::Zero();
};

}  // namespace ftc::sim
