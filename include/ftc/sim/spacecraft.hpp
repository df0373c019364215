#pragma once
// Rigid spacecraft attitude in Euler angles on a circular orbit (paper §6 and Appendix B).
//
// X1 = (roll, pitch, yaw) in rad, X2 their rates in rad/s, four actuators. f(X) contains the
// gyroscopic coupling (I_y - I_z)/I_x x5 x6, ... and the orbital-rate terms in ω0 and ω0²;
// G is the constant actuator-distribution matrix of eq. (B.4).
#include <array>

#include "ftc/sim/plant.hpp"

namespace ftc::sim {

struct SpacecraftParams {
  std::array<double, 3> inertia{20.0, 17.0, 15.0};  // Ix, Iy, Iz in kg·m² (not in the paper)
  double orbital_rate = 1.1e-3;                     // ω0 in rad/s (not in the paper)
};

class Spacecraft final : public Plant {
 public:
  explicit Spacecraft(const SpacecraftParams& params = {});

  Vec3 f(const State& x) const override;
  Vec3 f(const State& x, PlantWorkspace& ws) const override;
  Mat34 G(const State&) const override { return G_; }
  bool input_matrix_is_constant() const override { return true; }
  Mat43 G_pinv(const State&) const override { return G_pinv_; }
  std::string model() const override { return "spacecraft"; }

  const SpacecraftParams& params() const { return params_; }

  // The actuator-distribution matrix of eq. (B.4).
  static Mat34 distribution_matrix();

 private:
  Vec3 f_trig(const State& x, const double (&s)[3], const double (&c)[3]) const;

  SpacecraftParams params_;
  double kx_, ky_, kz_;  // (Iy-Iz)/Ix, (Iz-Ix)/Iy, (Ix-Iy)/Iz
  Mat34 G_;
  Mat43 G_pinv_;  // computed once: G is constant
};

}  // namespace ftc::sim
