#pragma once
// Full-order sliding-mode controller (paper Appendix D; the sign of D.4 corrected, SPEC §5).
//
//   sF   = a + C(X),   C(X) = c2 sig^α2(X2) + c1 sig^α1(X1)
//   u_d  = -G⁺ (f(X) + C(X) + ur)
//   ur  += Ts · K · sigm(sF)           (ur(0) = 0; D.4 prints -K, which diverges)
//
// Units: a rad/s², sF rad/s², ur rad/s², K = Π+ζ in rad/s³. Model-based.
#include "ftc/sim/controller.hpp"
#include "ftc/sim/plant_model.hpp"
#include "ftc/sim/sliding.hpp"

namespace ftc::sim {

class Fosmc final : public Controller {
 public:
  Fosmc(const ControllerConfig& config, const Plant& plant, double sample_time);

  void reset() override { ur_.setZero(); }
  Vec4 step(const Measurement& m) override;
  using Controller::step;
  const ControllerConfig& config() const override { return config_; }
  double sample_time() const override { return Ts_; }

 private:
  ControllerConfig config_;
  detail::PlantModel plant_;
  FosmTerm fosm_;  // C(X)
  double Ts_;
  Vec3 ur_ = Vec3::Zero();
};

}  // namespace ftc::sim
