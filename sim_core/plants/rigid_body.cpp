#include "ftc/sim/rigid_body.hpp"

#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <Eigen/QR>
#include <algorithm>
#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include "checks.hpp"
#include "ftc/sim/elementary.hpp"
#include "ftc/sim/vehicles.hpp"
#include "plants/hover.hpp"
#include "plants/kinds.hpp"
#include "plants/plant_adapter.hpp"
#include "plants/rigid_body_dynamics.hpp"

namespace ftc::sim {

namespace {

constexpr int MA = kMaxBodyActuators;

BodyTrig<double> trig_of(const RigidBody::State& x) {
  BodyTrig<double> g{0.0, 1.0, 0.0, 1.0, 1.0};
  math::sincos(x[0], g.sf, g.cf);
  math::sincos(x[1], g.st, g.ct);
  g.ict = 1.0 / g.ct;
  return g;
}

}  // namespace

RigidBody::RigidBody(const RigidBodyParams& params) : params_(params) {
  std::vector<FieldError> errs = inertia_errors(params.inertia, "/inertia");
  if (params.actuators < 3 || params.actuators > MA)
    errs.push_back({"/actuators", "expected 3 to " + std::to_string(MA) + " actuators, got " +
                                      std::to_string(params.actuators)});
  throw_if_errors("plant", std::move(errs));
  const int m = params.actuators;
  J_ = Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(params.inertia.data());
  diagonal_ = J_(0, 1) == 0.0 && J_(0, 2) == 0.0 && J_(1, 2) == 0.0;
  J_inv_ = J_.inverse();
  D_.setZero();
  for (int k = 0; k < 3; ++k)
    for (int j = 0; j < m; ++j) D_(k, j) = params.torque[static_cast<std::size_t>(k * MA + j)];
  Dp_.setZero();
  const auto& d = params.closed_form_ddt;
  if (!std::isnan(d[0])) {
    for (int j = 0; j < m; ++j)
      for (int k = 0; k < 3; ++k) Dp_(j, k) = D_(k, j) / d[static_cast<std::size_t>(k)];
  } else {
    const Mat<3, 3> DDt = D_ * D_.transpose();
    Eigen::FullPivLU<Mat<3, 3>> lu(DDt);
    if (!lu.isInvertible())
      throw InputError("plant", "/actuators", "the actuators' torques do not span R³");
    Dp_ = D_.transpose() * DDt.inverse();
  }
}

// The class's side of the lane code (plants/rigid_body_dynamics.hpp): its constants as the lanes
// read them, and the trigonometry of x (none with body rates).
struct RigidBody::Terms {
  BodyTerms<double> b;
  BodyTrig<double> g{0.0, 1.0, 0.0, 1.0, 1.0};
};

RigidBody::Terms RigidBody::terms(const State& x) const {
  Terms t;
  const auto k = f_constants();
  t.b.load([&](int i) { return k[static_cast<std::size_t>(i)]; }, diagonal_);
  if (params_.kinematics == BodyKinematics::euler_321) t.g = trig_of(x);
  return t;
}

RigidBody::Vector RigidBody::f(const State& x) const {
  const Terms t = terms(x);
  double out[3];
  body_f<double>(t.b, t.g, x.data(), out);
  return Vector(out[0], out[1], out[2]);
}

RigidBody::InputMatrix RigidBody::G(const State& x) const {
  InputMatrix G = J_inv_ * D_;
  if (params_.kinematics == BodyKinematics::body_rates) return G;
  const BodyTrig<double> g = trig_of(x);
  for (int j = 0; j < MA; ++j) {
    const double y[3] = {G(0, j), G(1, j), G(2, j)};
    double z[3];
    euler_W_inv<double>(g, y, z);
    for (int k = 0; k < 3; ++k) G(k, j) = z[k];
  }
  return G;
}

RigidBody::InputInverse RigidBody::G_pinv(const State& x) const {
  const Terms t = terms(x);
  double out[MA * 3];
  body_pinv<double>(t.b, t.g, out);
  InputInverse P;
  for (int j = 0; j < MA; ++j)
    for (int c = 0; c < 3; ++c) P(j, c) = out[j * 3 + c];
  return P;
}

std::array<double, RigidBodyConstants::kCount> RigidBody::f_constants() const {
  using K = RigidBodyConstants;
  std::array<double, K::kCount> c{};
  c[K::kEuler] = params_.kinematics == BodyKinematics::euler_321 ? 1.0 : 0.0;
  c[K::kDiagonal] = diagonal_ ? 1.0 : 0.0;
  const auto& J = params_.inertia;
  const double j6[6] = {J[0], J[4], J[8], J[1], J[2], J[5]};  // xx yy zz xy xz yz
  for (int i = 0; i < 6; ++i) c[static_cast<std::size_t>(K::kJ + i)] = j6[i];
  for (int k = 0; k < 3; ++k)
    for (int j = 0; j < MA; ++j) c[static_cast<std::size_t>(K::kD + k * MA + j)] = D_(k, j);
  for (int j = 0; j < MA; ++j)
    for (int k = 0; k < 3; ++k) c[static_cast<std::size_t>(K::kDpinv + j * 3 + k)] = Dp_(j, k);
  c[K::kM] = params_.actuators;
  return c;
}

RigidBody::ThrustRange RigidBody::thrust_range() const {
  ThrustRange r;
  for (int j = 0; j < MA; ++j) {
    const auto i = static_cast<std::size_t>(j);
    r.floor[i] = params_.u0[i] + params_.lo[i];
    r.cap[i] = params_.u0[i] + params_.hi[i];
  }
  return r;
}

bool RigidBody::trim_feasible(const std::array<bool, MA>& stuck,
                              const std::array<double, MA>& stuck_at,
                              const std::array<double, MA>& lost, const ThrustRange& range) const {
  if (params_.weight <= 0.0) return true;  // no operating point: zero torque, which any hold
  const int m = params_.actuators;
  const Eigen::MatrixXd A = D_.leftCols(m);
  const auto span = [m](const auto& a) { return std::span(a.data(), static_cast<std::size_t>(m)); };
  const double scale =
      *std::max_element(params_.max_thrust.begin(), params_.max_thrust.begin() + m);
  return detail::hover_margin(A, params_.weight, span(stuck), span(stuck_at), span(lost),
                              span(range.floor), span(range.cap), scale) > 1e-9 * scale;
}

}  // namespace ftc::sim
