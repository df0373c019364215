#include "ftc/sim/spacecraft.hpp"

#include <Eigen/LU>
#include <cmath>
#include <vector>

#include "checks.hpp"

namespace ftc::sim {

Mat34 Spacecraft::distribution_matrix() {
  Mat34 g;
  g << 0.67, 0.67, 0.67, 0.67,   //
      0.69, -0.69, -0.69, 0.69,  //
      0.28, 0.28, -0.28, -0.28;
  return g;
}

Spacecraft::Spacecraft(const SpacecraftParams& params) : params_(params) {
  std::vector<FieldError> errs;
  for (int i = 0; i < 3; ++i)
    detail::check_positive(errs, "/inertia/" + std::to_string(i), params.inertia[i]);
  detail::check_non_negative(errs, "/orbital_rate", params.orbital_rate);
  throw_if_errors("plant", std::move(errs));

  const double Ix = params.inertia[0], Iy = params.inertia[1], Iz = params.inertia[2];
  kx_ = (Iy - Iz) / Ix;
  ky_ = (Iz - Ix) / Iy;
  kz_ = (Ix - Iy) / Iz;
  G_ = distribution_matrix();
  const Eigen::Matrix3d GGt = G_ * G_.transpose();
  G_pinv_ = G_.transpose() * GGt.inverse();
}

Vec3 Spacecraft::f(const State& x) const {
  double s[3], c[3];
  for (int i = 0; i < 3; ++i) {
    s[i] = std::sin(x[i]);
    c[i] = std::cos(x[i]);
  }
  return f_trig(x, s, c);
}

}  // namespace ftc::sim
