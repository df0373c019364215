#include "ftc/sim/rigid_body.hpp"

#include <Eigen/LU>
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
  const auto& J = params.inertia;
  diagonal_ = J[1] == 0.0 && J[2] == 0.0 && J[5] == 0.0;
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
  constants_ = constants();
}

// The class's side of the lane code (plants/rigid_body_dynamics.hpp): its constants as the lanes
// read them, and the trigonometry of x (none with body rates).
struct RigidBody::Terms {
  BodyTerms<double> b;
  BodyTrig<double> g{0.0, 1.0, 0.0, 1.0, 1.0};
};

RigidBody::Terms RigidBody::terms(const State& x) const {
  Terms t;
  t.b.load([&](int i) { return constants_[static_cast<std::size_t>(i)]; });
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
  const Terms t = terms(x);
  InputMatrix G;
  for (int j = 0; j < MA; ++j) {
    const double a[3] = {t.b.G0[j], t.b.G0[MA + j], t.b.G0[2 * MA + j]};
    double z[3] = {a[0], a[1], a[2]};
    if (params_.kinematics == BodyKinematics::euler_321) euler_W_inv<double>(t.g, a, z);
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

std::array<double, RigidBodyConstants::kCount> RigidBody::constants() const {
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
  const int m = params_.actuators;
  const Eigen::MatrixXd A = D_.leftCols(m);
  const auto span = [m](const auto& a) { return std::span(a.data(), static_cast<std::size_t>(m)); };
  if (params_.weight > 0.0) {  // rotors: hover
    const double scale =
        *std::max_element(params_.max_thrust.begin(), params_.max_thrust.begin() + m);
    return detail::hold_margin(A, params_.weight, span(stuck), span(stuck_at), span(lost),
                               span(range.floor), span(range.cap), scale) > 1e-9 * scale;
  }
  // Wheels or thrusters: zero torque, which u = 0 gives unless one is stuck; then the others
  // must cancel its torque strictly within their limits (with none, any torque can be made).
  if (std::none_of(stuck.begin(), stuck.begin() + m, [](bool s) { return s; })) return true;
  double scale = 0.0;
  for (int j = 0; j < m; ++j)
    for (const double b : {range.floor[static_cast<std::size_t>(j)],
                           range.cap[static_cast<std::size_t>(j)]})
      if (std::isfinite(b)) scale = std::max(scale, std::abs(b));
  if (scale == 0.0) return true;
  return detail::hold_margin(A, 0.0, span(stuck), span(stuck_at), span(lost), span(range.floor),
                             span(range.cap), scale) > 1e-9 * scale;
}

}  // namespace ftc::sim
