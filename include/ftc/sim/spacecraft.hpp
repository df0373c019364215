#pragma once
// Rigid spacecraft attitude in Euler angles on a circular orbit (paper §6 and Appendix B).
//
// n = 3, m = 4. X1 = (roll, pitch, yaw) in rad, X2 their rates in rad/s. f(X) contains the
// gyroscopic coupling (I_y - I_z)/I_x x5 x6, ... and the orbital-rate terms in ω0 and ω0²
// (rad/s²); G is the constant actuator-distribution matrix of eq. (B.4), whose right inverse is
// computed once.
#include <array>

#include "ftc/sim/plant.hpp"

namespace ftc::sim {

struct SpacecraftParams {
  std::array<double, 3> inertia{20.0, 17.0, 15.0};  // Ix, Iy, Iz in kg·m² (not in the paper)
  double orbital_rate = 1.1e-3;                     // ω0 in rad/s (not in the paper)
};

struct PlantSpec;
// The parameters of a spacecraft plant as a job or gains file gives them (PlantSpec, see
// plants.hpp); throws InputError when the spec is of another model or its values are invalid.
SpacecraftParams spacecraft_params(const PlantSpec& spec);

class Spacecraft final : public Plant<3, 4> {
 public:
  // Scratch space of one simulation for evaluating f at the nearby states of successive RK4
  // stages (defined in sim_core; the simulator owns one).
  struct Workspace;

  // Throws InputError naming a non-positive inertia or a negative orbital rate.
  explicit Spacecraft(const SpacecraftParams& params = {});

  Vector f(const State& x) const override;
  // The same f(X), reusing work kept in `ws` (equal to f(x) within an ulp).
  Vector f(const State& x, Workspace& ws) const;
  InputMatrix G(const State&) const override { return G_; }
  bool input_matrix_is_constant() const override { return true; }
  InputInverse G_pinv(const State&) const override { return G_pinv_; }
  std::string model() const override { return "spacecraft"; }

  const SpacecraftParams& params() const { return params_; }
  // The constants f(X) is built from: (Iy-Iz)/Ix, (Iz-Ix)/Iy, (Ix-Iy)/Iz and ω0.
  std::array<double, 4> f_constants() const { return {kx_, ky_, kz_, params_.orbital_rate}; }

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
