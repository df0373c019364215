#pragma once
// PI full-order sliding-mode controller (paper eqs. 7, 11–13; SPEC §5).
//
//   sF   = a + C(X)                     full-order surface (eq. 8)
//   sPI  = Kp sF + Ki I,   I = ∫ sF dt  PI surface (eq. 7)
//   u_d  = -G⁺ (f(X) + C(X) + (Ki/Kp) I + ur)     (eq. 11 with eq. 12 divided through by Kp)
//   I   += Ts · sF
//   ur  += Ts · K · sigm(sPI)           (eq. 13 with the sigmoid for sign)
//
// Units: sF rad/s², I rad/s, ur rad/s², K = Π+ζ rad/s³, Kp dimensionless, Ki 1/s.
// With Kp = 1, Ki = 0 it issues exactly the commands of FOSMC. Model-based.
#include "ftc/sim/controller.hpp"
#include "ftc/sim/plant_model.hpp"
#include "ftc/sim/sliding.hpp"

namespace ftc::sim {

class PiFosmc final : public Controller {
 public:
  PiFosmc(const ControllerConfig& config, const Plant& plant, double sample_time);

  void reset() override {
    I_.setZero();
    ur_.setZero();
  }
  Vec4 step(const Measurement& m) override;
  using Controller::step;
  const ControllerConfig& config() const override { return config_; }
  double sample_time() const override { return Ts_; }

 private:
  ControllerConfig config_;
  detail::PlantModel plant_;
  FosmTerm fosm_;  // C(X)
  double Ts_;
  Vec3 I_ = Vec3::Zero();
  Vec3 ur_ = Vec3::Zero();
};

}  // namespace ftc::sim
