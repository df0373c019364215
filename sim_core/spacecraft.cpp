#include "ftc/sim/spacecraft.hpp"

#include <Eigen/LU>
#include <cmath>
#include <vector>

#include "checks.hpp"

namespace ftc::sim {

Mat34 Spacecraft::distribution_matrix() {
  Mat34 g;
  g << 0.67, 0.67, 0.67, 0.67,  //
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

// Appendix B (B.1–B.3) term by term, with the erratum of B.3 (s_2 x3 read as sin² x3).
// sin(2x) is formed as 2 sin x cos x to reuse the sines and cosines already computed.
Vec3 Spacecraft::f(const State& x) const {
  const double x4 = x[3], x5 = x[4], x6 = x[5];
  const double s1 = std::sin(x[0]), c1 = std::cos(x[0]);
  const double s2 = std::sin(x[1]), c2 = std::cos(x[1]);
  const double s3 = std::sin(x[2]), c3 = std::cos(x[2]);
  const double d1 = 2.0 * s1 * c1, d2 = 2.0 * s2 * c2, d3 = 2.0 * s3 * c3;
  const double w = params_.orbital_rate;
  const double w2h = 0.5 * w * w;   // ½ω0²
  const double w2t = 1.5 * w * w;   // 3/2 ω0²

  const double f1 = w * x6 * c3 * c2 - w * x5 * s3 * s2 +
                    kx_ * (x5 * x6 + w * x5 * c1 * s3 * s2 + w * x5 * c3 * s1 + w * x6 * c3 * c1 +
                           w2h * d3 * c1 * c1 * s2 + w2h * c3 * c3 * d1 -
                           w * x6 * s3 * s2 * s1 - w2h * s2 * s2 * s3 * s3 * d1 -
                           w * d2 * s2 * s1 * s1 - w2t * c2 * c2 * d1);
  const double f2 = w * x6 * s3 * c1 + w * x4 * c3 * s1 + w * x6 * c3 * s2 * s1 +
                    w * x5 * s3 * c2 * s1 + w * x4 * s3 * s2 * c1 +
                    ky_ * (x4 * x6 + w * x4 * c1 * s3 * s2 + w * x4 * c3 * s2 * s1 -
                           w * x6 * s3 * c2 - w2h * d2 * s3 * s3 * c1 - w2h * c2 * s1 * d3 +
                           w2t * d2 * c1);
  const double f3 = w * x4 * s1 * s3 * s2 - w * x6 * c1 * c3 * s2 - w * x5 * c1 * s3 * c2 +
                    w * x6 * s3 * s1 - w * x4 * c3 * c1 +
                    kz_ * (x4 * x5 + w * x4 * c3 * c1 - w * x4 * s3 * s2 * s1 -
                           w * x5 * s3 * c2 - w2h * d3 * c2 * c1 - w2h * s3 * s3 * s1 * d2 -
                           w2t * d2 * s1);
  return Vec3(f1, f2, f3);
}

}  // namespace ftc::sim
