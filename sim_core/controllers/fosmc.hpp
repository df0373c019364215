#pragma once
// Full-order sliding-mode controller (paper Appendix D; the sign of D.4 corrected, SPEC §5).
//
//   sF   = a + C(X),   C(X) = c2 sig^α2(X2) + c1 sig^α1(X1)
//   u_d  = -G⁺ (f(X) + C(X) + ur)
//   ur  += Ts · K · sigm(sF)           (ur(0) = 0; D.4 prints -K, which diverges)
//
// Units (spacecraft): a rad/s², sF rad/s², ur rad/s², K = Π+ζ in rad/s³. Model-based.
#include "checks.hpp"
#include "controllers/plant_model.hpp"
#include "controllers/sliding.hpp"
#include "ftc/sim/controller.hpp"

namespace ftc::sim {

template <int N, int M>
class Fosmc final : public Controller<N, M> {
 public:
  Fosmc(const ControllerConfig& config, const Plant<N, M>& plant, double sample_time)
      : config_(detail::checked_config(config, sample_time)),
        plant_(plant),
        fosm_(config_.c1, config_.c2, config_.alpha1, config_.alpha2),
        Ts_(sample_time) {}

  void reset() override { ur_.setZero(); }
  using Controller<N, M>::step;
  Vec<M> step(const Measurement<N>& m) override {
    const ControllerConfig& c = config_;
    const Vec<N> fx = plant_.f(m);
    const Vec<N> C = fosm_(m.X1, m.X2);
    const Vec<N> sF = m.a + C;

    Vec<N> v = fx + C;
    v += ur_;
    const Vec<M> u = -plant_.G_pinv_times(m, v);

    ur_ += (Ts_ * c.switching_gain) * sigm(sF, c.theta);
    return u;
  }
  const ControllerConfig& config() const override { return config_; }
  double sample_time() const override { return Ts_; }

 private:
  ControllerConfig config_;
  detail::PlantModel<N, M> plant_;
  FosmTerm fosm_;  // C(X)
  double Ts_;
  Vec<N> ur_ = Vec<N>::Zero();
};

}  // namespace ftc::sim
