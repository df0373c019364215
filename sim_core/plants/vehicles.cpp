// The rigid_body and multirotor plants as jobs describe them (ftc/sim/vehicles.hpp): presets,
// validation at JSON paths, the RigidBody each describes, their flattened values and their
// PlantKinds.
#include "ftc/sim/vehicles.hpp"

#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <Eigen/QR>
#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>

#include "checks.hpp"
#include "ftc/sim/elementary.hpp"
#include "plants/kinds.hpp"
#include "plants/plant_adapter.hpp"

namespace ftc::sim {

namespace {

constexpr double kHalfSqrt2 = 0.7071067811865476;  // sin 45°, correctly rounded
constexpr double kSin22 = 0.3826834323650898;      // sin 22.5°
constexpr double kCos22 = 0.9238795325112867;      // cos 22.5°
constexpr double kSin30 = 0.5, kCos30 = 0.8660254037844386;

std::string num(double v) { return detail::fmt_num(v); }

// sin α_i and cos α_i of a preset's rotors, correctly rounded (not through a libm), so that
// hexa_x's are the hexarotor's (plants/hexarotor_dynamics.hpp).
struct Layout {
  std::vector<double> s, c;
};
Layout preset_layout(const std::string& name) {
  if (name == "quad_x")
    return {{kHalfSqrt2, kHalfSqrt2, -kHalfSqrt2, -kHalfSqrt2},
            {kHalfSqrt2, -kHalfSqrt2, -kHalfSqrt2, kHalfSqrt2}};
  if (name == "quad_plus") return {{0.0, 1.0, 0.0, -1.0}, {1.0, 0.0, -1.0, 0.0}};
  if (name == "hexa_x")
    return {{kSin30, 1.0, kSin30, -kSin30, -1.0, -kSin30},
            {kCos30, 0.0, -kCos30, -kCos30, 0.0, kCos30}};
  if (name == "octa_x")
    return {{kSin22, kCos22, kCos22, kSin22, -kSin22, -kCos22, -kCos22, -kSin22},
            {kCos22, kSin22, -kSin22, -kCos22, -kCos22, -kSin22, kSin22, kCos22}};
  return {};
}

int code_of(const std::vector<std::string>& names, const std::string& name) {
  for (std::size_t i = 0; i < names.size(); ++i)
    if (names[i] == name) return static_cast<int>(i) + 1;
  return 0;  // "": the explicit list
}

// The rotors of a spec: its list, or its preset's at its arm length.
std::vector<RotorSpec> rotors_of(const MultirotorSpec& s) {
  if (s.preset.empty()) return s.rotors;
  const Layout L = preset_layout(s.preset);
  std::vector<RotorSpec> r(L.s.size());
  for (std::size_t i = 0; i < r.size(); ++i) {
    r[i].position = {s.arm_length * L.c[i], s.arm_length * L.s[i]};
    r[i].spin = i % 2 == 0 ? 1 : -1;
    r[i].max_thrust = s.max_thrust;
    r[i].moment_constant = s.moment_constant;
  }
  return r;
}

// Unit axes of a spec (its preset's, or its own normalised).
std::vector<std::array<double, 3>> axes_of(const RigidBodySpec& s) {
  if (s.preset == "orthogonal") return {{1.0, 0.0, 0.0}, {0.0, 1.0, 0.0}, {0.0, 0.0, 1.0}};
  if (s.preset == "nasa") {
    const double k = 1.0 / std::sqrt(3.0);
    return {{1.0, 0.0, 0.0}, {0.0, 1.0, 0.0}, {0.0, 0.0, 1.0}, {k, k, k}};
  }
  if (s.preset == "pyramid") {
    double sb, cb;
    if (s.beta_deg == kPyramidBetaDeg) {  // exactly asin(1/√3)
      sb = 1.0 / std::sqrt(3.0);
      cb = std::sqrt(2.0 / 3.0);
    } else {
      math::sincos(s.beta_deg * (3.14159265358979323846 / 180.0), sb, cb);
    }
    const double h = cb * kHalfSqrt2;
    return {{h, h, sb}, {-h, h, sb}, {-h, -h, sb}, {h, -h, sb}};
  }
  std::vector<std::array<double, 3>> a = s.axes;
  for (auto& v : a) {
    const double n = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    for (double& x : v) x /= n;
  }
  return a;
}

// The simulated plant's torque per unit command of each actuator: its axis turned by its
// misalignment and scaled by its effectiveness (the model's axes when a spec has neither).
std::vector<std::array<double, 3>> true_axes(const RigidBodySpec& s) {
  std::vector<std::array<double, 3>> axes = axes_of(s);
  for (std::size_t j = 0; j < axes.size(); ++j) {
    axes[j] = misaligned_axis(axes[j],
                              s.actuator_misalignment.empty() ? 0.0 : s.actuator_misalignment[j]);
    const double k = s.actuator_scale.empty() ? 1.0 : s.actuator_scale[j];
    for (double& x : axes[j]) x = k * x;
  }
  return axes;
}

// D Dᵀ's eigenvalues, ascending, of the columns `axes`: the smallest against the largest says
// whether they span R³.
Eigen::Vector3d span_eigenvalues(const std::vector<std::array<double, 3>>& axes) {
  Eigen::Matrix3d DDt = Eigen::Matrix3d::Zero();
  for (const auto& v : axes) {
    const Eigen::Vector3d d(v[0], v[1], v[2]);
    DDt += d * d.transpose();
  }
  return Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(DDt).eigenvalues();
}

// The rank of a multirotor's torques per newton (3 × rotors).
Eigen::Index torque_rank(const Eigen::MatrixXd& A) {
  Eigen::FullPivLU<Eigen::MatrixXd> lu(A);
  lu.setThreshold(1e-9);
  return lu.rank();
}

double limit_of(const std::vector<double>& max, std::size_t j) {
  if (max.empty()) return 0.0;
  return max.size() == 1 ? max[0] : (j < max.size() ? max[j] : 0.0);
}

// A scenario's per-actuator departures from the model (actuator_scale ≥ 0, misalignment in
// [−π, π]): none, or one finite value per actuator.
void check_per_actuator(std::vector<FieldError>& errs, const std::vector<double>& v, int m,
                        const std::string& path, bool angle) {
  if (v.empty()) return;
  if (static_cast<int>(v.size()) != m) {
    errs.push_back({path, "expected one value per actuator (" + std::to_string(m) + "), got " +
                              std::to_string(v.size())});
    return;
  }
  constexpr double kPi = 3.14159265358979323846;
  for (std::size_t j = 0; j < v.size(); ++j) {
    const bool ok = angle ? std::isfinite(v[j]) && std::abs(v[j]) <= kPi
                          : std::isfinite(v[j]) && v[j] >= 0.0;
    if (!ok)
      errs.push_back({path + "/" + std::to_string(j),
                      angle ? "a misalignment must be an angle in [-pi, pi] rad (got " +
                                  num(v[j]) + ")"
                            : "an actuator's effectiveness must be a finite number >= 0 (got " +
                                  num(v[j]) + ")"});
  }
}

}  // namespace

std::array<double, 3> misaligned_axis(const std::array<double, 3>& a, double angle) {
  if (angle == 0.0) return a;
  // k = a × ẑ = (a_y, −a_x, 0), or a × x̂ = (0, a_z, −a_y) for an axis along ẑ.
  std::array<double, 3> k{a[1], -a[0], 0.0};
  double n = std::sqrt(k[0] * k[0] + k[1] * k[1]);
  if (n < 1e-12) {
    k = {0.0, a[2], -a[1]};
    n = std::sqrt(k[1] * k[1] + k[2] * k[2]);
  }
  for (double& x : k) x /= n;
  // Rodrigues with k ⊥ a: a cos θ + (k × a) sin θ.
  const std::array<double, 3> kxa{k[1] * a[2] - k[2] * a[1], k[2] * a[0] - k[0] * a[2],
                                  k[0] * a[1] - k[1] * a[0]};
  double s, c;
  math::sincos(angle, s, c);
  return {a[0] * c + kxa[0] * s, a[1] * c + kxa[1] * s, a[2] * c + kxa[2] * s};
}

const std::vector<std::string>& body_presets() {
  static const std::vector<std::string> v = {"orthogonal", "pyramid", "nasa"};
  return v;
}
const std::vector<std::string>& rotor_presets() {
  static const std::vector<std::string> v = {"quad_x", "quad_plus", "hexa_x", "octa_x"};
  return v;
}

int actuator_count(const RigidBodySpec& s) {
  if (s.preset == "orthogonal") return 3;
  if (!s.preset.empty()) return 4;
  return static_cast<int>(s.axes.size());
}
int actuator_count(const MultirotorSpec& s) {
  return s.preset.empty() ? static_cast<int>(s.rotors.size())
                          : static_cast<int>(preset_layout(s.preset).s.size());
}

std::vector<FieldError> inertia_errors(const std::array<double, 9>& J, const std::string& path) {
  std::vector<FieldError> errs;
  for (std::size_t i = 0; i < 9; ++i)
    if (!std::isfinite(J[i]))
      errs.push_back({path + "/" + std::to_string(i / 3) + "/" + std::to_string(i % 3),
                      "must be a finite number (got " + num(J[i]) + ")"});
  if (!errs.empty()) return errs;
  for (int r = 0; r < 3; ++r)
    for (int c = r + 1; c < 3; ++c)
      if (J[static_cast<std::size_t>(3 * r + c)] != J[static_cast<std::size_t>(3 * c + r)])
        errs.push_back({path + "/" + std::to_string(c) + "/" + std::to_string(r),
                        "the inertia tensor must be symmetric: [" + std::to_string(r) + "][" +
                            std::to_string(c) + "] is " +
                            num(J[static_cast<std::size_t>(3 * r + c)]) + " but [" +
                            std::to_string(c) + "][" + std::to_string(r) + "] is " +
                            num(J[static_cast<std::size_t>(3 * c + r)])});
  if (!errs.empty()) return errs;
  // Sylvester's criterion: every leading minor positive.
  const double m1 = J[0], m2 = J[0] * J[4] - J[1] * J[3];
  const double m3 = J[0] * (J[4] * J[8] - J[5] * J[7]) - J[1] * (J[3] * J[8] - J[5] * J[6]) +
                    J[2] * (J[3] * J[7] - J[4] * J[6]);
  const bool diagonal = J[1] == 0.0 && J[2] == 0.0 && J[5] == 0.0;
  if (diagonal) {
    for (int i = 0; i < 3; ++i)
      if (!(J[static_cast<std::size_t>(4 * i)] > 0.0))
        errs.push_back(
            {path + "/" + std::to_string(i), "a principal moment of inertia must be > 0 (got " +
                                                 num(J[static_cast<std::size_t>(4 * i)]) + ")"});
    return errs;
  }
  const char* test = !(m1 > 0.0)   ? "its [0][0] entry"
                     : !(m2 > 0.0) ? "its leading 2×2 minor"
                     : !(m3 > 0.0) ? "its determinant"
                                   : nullptr;
  if (test)
    errs.push_back({path, std::string("the inertia tensor must be positive definite, but ") + test +
                              " is " +
                              num(!(m1 > 0.0)   ? m1
                                  : !(m2 > 0.0) ? m2
                                                : m3) +
                              " (Sylvester's test: every leading minor > 0)"});
  return errs;
}

std::vector<FieldError> validate(const RigidBodySpec& s, const std::string& path) {
  std::vector<FieldError> errs = inertia_errors(s.inertia, path + "/inertia");
  const std::string a = path + "/actuators";
  if (!s.preset.empty() && code_of(body_presets(), s.preset) == 0)
    errs.push_back({a + "/preset",
                    "unknown preset \"" + s.preset + "\" (supported: orthogonal, pyramid, nasa)"});
  if (s.preset == "pyramid" && !(std::abs(s.beta_deg) > 0.0 && std::abs(s.beta_deg) < 90.0))
    errs.push_back({a + "/beta_deg",
                    "the wheels' elevation must be strictly between 0 and 90 "
                    "degrees, or they cannot span all three axes (got " +
                        num(s.beta_deg) + ")"});
  const int m = actuator_count(s);
  if (s.preset.empty()) {
    if (m < 3 || m > kMaxBodyActuators)
      errs.push_back({a + "/axes", "expected 3 to " + std::to_string(kMaxBodyActuators) +
                                       " actuator axes, got " + std::to_string(m)});
    for (std::size_t j = 0; j < s.axes.size(); ++j) {
      const auto& v = s.axes[j];
      const double n2 = v[0] * v[0] + v[1] * v[1] + v[2] * v[2];
      if (!std::isfinite(n2) || !(n2 > 0.0))
        errs.push_back({a + "/axes/" + std::to_string(j),
                        "an actuator axis must be a finite, non-zero vector"});
    }
  }
  if (!s.max.empty() && s.max.size() != 1 && static_cast<int>(s.max.size()) != m)
    errs.push_back({a + "/max", "expected one limit for every actuator or one per actuator (" +
                                    std::to_string(m) + "), got " + std::to_string(s.max.size())});
  for (std::size_t j = 0; j < s.max.size(); ++j)
    if (!(s.max[j] > 0.0) || !std::isfinite(s.max[j])) {
      std::string where = a + "/max";
      if (s.max.size() > 1) where += "/" + std::to_string(j);
      errs.push_back({std::move(where), "an actuator's limit must be a finite number > 0 (got " +
                                            num(s.max[j]) + ")"});
    }
  check_per_actuator(errs, s.actuator_scale, m, path + "/actuator_scale", false);
  check_per_actuator(errs, s.actuator_misalignment, m, path + "/actuator_misalignment", true);
  if (!errs.empty()) return errs;
  // The axes must span R³: D Dᵀ's smallest eigenvalue against its largest.
  const Eigen::Vector3d ev = span_eigenvalues(axes_of(s));
  if (!(ev[0] > 1e-12 * ev[2]))
    errs.push_back({s.preset.empty() ? a + "/axes" : a,
                    "the actuator axes must span R³ (torque about every axis), but they lie in "
                    "a plane or on a line: D Dᵀ has eigenvalues " +
                        num(ev[0]) + ", " + num(ev[1]) + ", " + num(ev[2])});
  // The simulated plant's actuators (a scenario's actuator_scale and actuator_misalignment)
  // must span R³ as well: a wheel at effectiveness 0, or one turned onto another's axis, can
  // leave them in a plane, and no plant can be built (simulated) from that.
  if (errs.empty() && (!s.actuator_scale.empty() || !s.actuator_misalignment.empty())) {
    const Eigen::Vector3d tv = span_eigenvalues(true_axes(s));
    if (!(tv[0] > 1e-12 * tv[2]))
      errs.push_back({path + (s.actuator_scale.empty() ? "/actuator_misalignment"
                                                        : "/actuator_scale"),
                      "with these values the simulated plant's actuators no longer span R³ "
                      "(their torques lie in a plane or on a line: D Dᵀ has eigenvalues " +
                          num(tv[0]) + ", " + num(tv[1]) + ", " + num(tv[2]) +
                          "); a wholly lost actuator is a loss_of_effectiveness fault"});
  }
  return errs;
}

std::vector<double> hover_thrusts(const MultirotorSpec& s) {
  const std::vector<RotorSpec> r = rotors_of(s);
  const double weight = s.mass * s.gravity;
  const auto n = static_cast<Eigen::Index>(r.size());
  if (!s.preset.empty()) return std::vector<double>(r.size(), weight / static_cast<double>(n));
  Eigen::MatrixXd E(4, n);
  for (Eigen::Index i = 0; i < n; ++i) {
    const RotorSpec& q = r[static_cast<std::size_t>(i)];
    E(0, i) = q.position[1];
    E(1, i) = -q.position[0];
    E(2, i) = q.spin * q.moment_constant;
    E(3, i) = 1.0;
  }
  const Eigen::Vector4d c(0.0, 0.0, 0.0, weight);
  const Eigen::VectorXd T = E.completeOrthogonalDecomposition().solve(c);
  if ((E * T - c).norm() > 1e-9 * weight)
    return std::vector<double>(r.size(), std::numeric_limits<double>::quiet_NaN());
  return {T.data(), T.data() + T.size()};
}

std::vector<FieldError> validate(const MultirotorSpec& s, const std::string& path) {
  std::vector<FieldError> errs = inertia_errors(s.inertia, path + "/inertia");
  detail::check_positive(errs, path + "/mass", s.mass);
  detail::check_positive(errs, path + "/gravity", s.gravity);
  const std::string rp = path + "/rotors";
  if (!s.preset.empty()) {
    if (code_of(rotor_presets(), s.preset) == 0)
      errs.push_back({rp + "/preset", "unknown preset \"" + s.preset +
                                          "\" (supported: quad_x, quad_plus, hexa_x, octa_x)"});
    detail::check_positive(errs, rp + "/arm_length", s.arm_length);
    detail::check_positive(errs, rp + "/max_thrust", s.max_thrust);
    detail::check_positive(errs, rp + "/moment_constant", s.moment_constant);
  } else {
    const int m = actuator_count(s);
    if (m < 4 || m > kMaxBodyActuators)
      errs.push_back({rp, "expected 4 to " + std::to_string(kMaxBodyActuators) + " rotors, got " +
                              std::to_string(m)});
    for (std::size_t i = 0; i < s.rotors.size(); ++i) {
      const std::string p = rp + "/" + std::to_string(i);
      const RotorSpec& q = s.rotors[i];
      for (int k = 0; k < 2; ++k)
        detail::check_finite(errs, p + "/position/" + std::to_string(k),
                             q.position[static_cast<std::size_t>(k)]);
      if (q.spin != 1 && q.spin != -1) errs.push_back({p + "/spin", "must be \"cw\" or \"ccw\""});
      detail::check_positive(errs, p + "/max_thrust", q.max_thrust);
      detail::check_positive(errs, p + "/moment_constant", q.moment_constant);
    }
  }
  check_per_actuator(errs, s.actuator_scale, actuator_count(s), path + "/actuator_scale", false);
  if (!errs.empty()) return errs;
  const std::vector<RotorSpec> r = rotors_of(s);
  Eigen::MatrixXd A(3, static_cast<Eigen::Index>(r.size()));
  for (std::size_t i = 0; i < r.size(); ++i)
    A.col(static_cast<Eigen::Index>(i)) << r[i].position[1], -r[i].position[0],
        r[i].spin * r[i].moment_constant;
  if (const Eigen::Index rank = torque_rank(A); rank < 3) {
    errs.push_back({rp,
                    "the rotors cannot make a torque about every axis (their torques per "
                    "newton span " +
                        std::to_string(rank) +
                        " dimensions of 3: rotors on a line, or every spin the same)"});
    return errs;
  }
  // The simulated plant's rotors (a scenario's actuator_scale) must too.
  if (!s.actuator_scale.empty()) {
    Eigen::MatrixXd As = A;
    for (Eigen::Index i = 0; i < As.cols(); ++i)
      As.col(i) *= s.actuator_scale[static_cast<std::size_t>(i)];
    if (const Eigen::Index rank = torque_rank(As); rank < 3) {
      errs.push_back({path + "/actuator_scale",
                      "with these values the simulated plant's rotors no longer make a torque "
                      "about every axis (their torques span " +
                          std::to_string(rank) +
                          " dimensions of 3); a wholly lost rotor is a loss_of_effectiveness "
                          "fault"});
      return errs;
    }
  }
  const std::vector<double> T = hover_thrusts(s);
  for (std::size_t i = 0; i < r.size(); ++i)
    if (!(T[i] > 0.0 && T[i] < r[i].max_thrust)) {
      errs.push_back(
          {std::isnan(T[i])   ? rp
           : s.preset.empty() ? rp + "/" + std::to_string(i)
                              : rp + "/max_thrust",
           std::isnan(T[i])
               ? std::string("the rotors cannot hold hover: no thrusts give zero torque and carry "
                             "the weight")
               : "the layout cannot hover: rotor " + std::to_string(i + 1) +
                     "'s hover thrust (the minimum-norm thrusts with zero torque that carry m g "
                     "= " +
                     num(s.mass * s.gravity) + " N) is " + num(T[i]) +
                     " N, not strictly between 0 and its max_thrust " + num(r[i].max_thrust) +
                     " N"});
      break;
    }
  return errs;
}

RigidBodyParams rigid_body_params(const RigidBodySpec& s) {
  throw_if_errors("plant", validate(s, ""));
  RigidBodyParams p;
  p.model = "rigid_body";
  p.kinematics = BodyKinematics::euler_321;
  p.inertia = s.inertia;
  // The simulated plant's axes and effectiveness (the model's: the axes as given, 1).
  const auto axes = true_axes(s);
  p.actuators = static_cast<int>(axes.size());
  for (std::size_t j = 0; j < axes.size(); ++j) {
    for (std::size_t k = 0; k < 3; ++k) p.torque[k * kMaxBodyActuators + j] = axes[j][k];
    const double lim = limit_of(s.max, j);
    if (lim > 0.0) {
      p.lo[j] = -lim;
      p.hi[j] = lim;
    }
  }
  return p;
}

RigidBodyParams multirotor_params(const MultirotorSpec& s) {
  throw_if_errors("plant", validate(s, ""));
  RigidBodyParams p;
  p.model = "multirotor";
  p.kinematics = BodyKinematics::body_rates;
  p.inertia = s.inertia;
  const std::vector<RotorSpec> r = rotors_of(s);
  const std::vector<double> T = hover_thrusts(s);
  p.actuators = static_cast<int>(r.size());
  for (std::size_t i = 0; i < r.size(); ++i) {
    const double scale = s.actuator_scale.empty() ? 1.0 : s.actuator_scale[i];
    p.torque[0 * kMaxBodyActuators + i] = scale * r[i].position[1];
    p.torque[1 * kMaxBodyActuators + i] = scale * -r[i].position[0];
    p.torque[2 * kMaxBodyActuators + i] = scale * (r[i].moment_constant * r[i].spin);
    p.u0[i] = T[i];
    p.lo[i] = -T[i];
    p.hi[i] = r[i].max_thrust - T[i];
    p.max_thrust[i] = r[i].max_thrust;
  }
  if (!s.preset.empty() && s.actuator_scale.empty()) {
    // A symmetric preset's A Aᵀ = diag(n l²/2, n l²/2, n κ²) exactly; formed as the hexarotor
    // forms its own, (3 l) l and (6 κ) κ.
    const double n = static_cast<double>(r.size());
    p.closed_form_ddt = {(0.5 * n) * s.arm_length * s.arm_length,
                         (0.5 * n) * s.arm_length * s.arm_length,
                         n * s.moment_constant * s.moment_constant};
  }
  p.weight = s.mass * s.gravity;
  return p;
}

// --- flattened values -------------------------------------------------------------------------

namespace {
// rigid_body: inertia 9, preset, beta_deg, m, axes 8×3, max 8 (0: none), the simulated plant's
// actuator_scale 8 (1: the model's) and actuator_misalignment 8 (0).
constexpr std::size_t kRbPreset = 9, kRbBeta = 10, kRbCount = 11, kRbAxes = 12, kRbMax = 36,
                      kRbScale = 44, kRbMisalignment = 52, kRbSize = 60;
// multirotor: inertia 9, mass, gravity, preset, arm_length, max_thrust, moment_constant (a
// preset's), m, x 8, y 8, spin 8, max_thrust 8, moment_constant 8.
constexpr std::size_t kMrMass = 9, kMrGravity = 10, kMrPreset = 11, kMrArm = 12, kMrTmax = 13,
                      kMrKappa = 14, kMrCount = 15, kMrX = 16, kMrY = 24, kMrSpin = 32,
                      kMrRotorTmax = 40, kMrRotorKappa = 48, kMrScale = 56, kMrSize = 64;

// A per-actuator list into its m slots (`fill` elsewhere), and back: empty when every one of
// the m is `fill` (the model's).
void put_per_actuator(std::vector<double>& v, std::size_t at, const std::vector<double>& list,
                      double fill) {
  for (std::size_t j = 0; j < static_cast<std::size_t>(kMaxBodyActuators); ++j)
    v[at + j] = j < list.size() ? list[j] : fill;
}
std::vector<double> get_per_actuator(const std::vector<double>& v, std::size_t at, int m,
                                     double fill) {
  const auto first = v.begin() + static_cast<long>(at);
  if (std::all_of(first, first + m, [fill](double x) { return x == fill; })) return {};
  return {first, first + m};
}
}  // namespace

std::vector<double> to_values(const RigidBodySpec& s) {
  std::vector<double> v(kRbSize, 0.0);
  std::copy(s.inertia.begin(), s.inertia.end(), v.begin());
  v[kRbPreset] = code_of(body_presets(), s.preset);
  v[kRbBeta] = s.beta_deg;
  const int m = actuator_count(s);
  v[kRbCount] = m;
  for (std::size_t j = 0; j < s.axes.size() && j < static_cast<std::size_t>(kMaxBodyActuators); ++j)
    for (std::size_t k = 0; k < 3; ++k) v[kRbAxes + 3 * j + k] = s.axes[j][k];
  for (std::size_t j = 0; j < static_cast<std::size_t>(std::clamp(m, 0, kMaxBodyActuators)); ++j)
    v[kRbMax + j] = limit_of(s.max, j);
  put_per_actuator(v, kRbScale, s.actuator_scale, 1.0);
  put_per_actuator(v, kRbMisalignment, s.actuator_misalignment, 0.0);
  return v;
}

RigidBodySpec rigid_body_spec(const std::vector<double>& v) {
  RigidBodySpec s;
  if (v.size() != kRbSize) return s;
  std::copy(v.begin(), v.begin() + 9, s.inertia.begin());
  const int code = static_cast<int>(v[kRbPreset]);
  s.preset = code >= 1 && code <= 3 ? body_presets()[static_cast<std::size_t>(code - 1)] : "";
  s.beta_deg = v[kRbBeta];
  const int m = std::clamp(static_cast<int>(v[kRbCount]), 0, kMaxBodyActuators);
  s.axes.clear();
  if (s.preset.empty())
    for (int j = 0; j < m; ++j) {
      const std::size_t at = kRbAxes + 3 * static_cast<std::size_t>(j);
      s.axes.push_back({v[at], v[at + 1], v[at + 2]});
    }
  s.max.clear();
  bool any = false, same = true;
  for (int j = 0; j < m; ++j) {
    any = any || v[kRbMax + static_cast<std::size_t>(j)] != 0.0;
    same = same && v[kRbMax + static_cast<std::size_t>(j)] == v[kRbMax];
  }
  if (any) {
    if (same)
      s.max = {v[kRbMax]};
    else
      s.max.assign(v.begin() + kRbMax, v.begin() + kRbMax + m);
  }
  s.actuator_scale = get_per_actuator(v, kRbScale, m, 1.0);
  s.actuator_misalignment = get_per_actuator(v, kRbMisalignment, m, 0.0);
  return s;
}

std::vector<double> to_values(const MultirotorSpec& s) {
  std::vector<double> v(kMrSize, 0.0);
  std::copy(s.inertia.begin(), s.inertia.end(), v.begin());
  v[kMrMass] = s.mass;
  v[kMrGravity] = s.gravity;
  v[kMrPreset] = code_of(rotor_presets(), s.preset);
  v[kMrArm] = s.arm_length;
  v[kMrTmax] = s.max_thrust;
  v[kMrKappa] = s.moment_constant;
  const std::vector<RotorSpec> r = rotors_of(s);
  v[kMrCount] = static_cast<double>(r.size());
  for (std::size_t i = 0; i < r.size() && i < static_cast<std::size_t>(kMaxBodyActuators); ++i) {
    v[kMrX + i] = r[i].position[0];
    v[kMrY + i] = r[i].position[1];
    v[kMrSpin + i] = r[i].spin;
    v[kMrRotorTmax + i] = r[i].max_thrust;
    v[kMrRotorKappa + i] = r[i].moment_constant;
  }
  put_per_actuator(v, kMrScale, s.actuator_scale, 1.0);
  return v;
}

MultirotorSpec multirotor_spec(const std::vector<double>& v) {
  MultirotorSpec s;
  if (v.size() != kMrSize) return s;
  std::copy(v.begin(), v.begin() + 9, s.inertia.begin());
  s.mass = v[kMrMass];
  s.gravity = v[kMrGravity];
  const int code = static_cast<int>(v[kMrPreset]);
  s.preset = code >= 1 && code <= 4 ? rotor_presets()[static_cast<std::size_t>(code - 1)] : "";
  s.arm_length = v[kMrArm];
  s.max_thrust = v[kMrTmax];
  s.moment_constant = v[kMrKappa];
  s.rotors.clear();
  if (s.preset.empty()) {
    const int m = std::clamp(static_cast<int>(v[kMrCount]), 0, kMaxBodyActuators);
    for (std::size_t i = 0; i < static_cast<std::size_t>(m); ++i) {
      RotorSpec q;
      q.position = {v[kMrX + i], v[kMrY + i]};
      q.spin = v[kMrSpin + i] < 0.0 ? -1 : 1;
      if (v[kMrSpin + i] != 1.0 && v[kMrSpin + i] != -1.0) q.spin = 0;  // refused by validate
      q.max_thrust = v[kMrRotorTmax + i];
      q.moment_constant = v[kMrRotorKappa + i];
      s.rotors.push_back(q);
    }
  }
  s.actuator_scale = get_per_actuator(
      v, kMrScale, std::clamp(static_cast<int>(v[kMrCount]), 0, kMaxBodyActuators), 1.0);
  return s;
}

}  // namespace ftc::sim

namespace ftc::sim::detail {

namespace {

std::vector<PlantParameter> inertia_parameter(const std::array<double, 9>& J) {
  return {{"inertia",
           {J.begin(), J.end()},
           Range::any(),
           "kg·m²",
           "the inertia tensor J (3 principal moments, or the symmetric 3×3 tensor)"}};
}

}  // namespace

PlantKind rigid_body_kind() {
  PlantKind k;
  k.model = "rigid_body";
  k.description =
      "a rigid body's attitude (3-2-1 Euler angles) with your inertia tensor and 3 to 8 "
      "actuators (reaction wheels or thrusters) along any axes or a preset; commands are "
      "torques in N·m";
  k.axes = 3;
  k.actuators = kMaxBodyActuators;
  const RigidBodySpec d;
  const std::vector<double> dv = to_values(d);
  k.parameters = inertia_parameter(d.inertia);
  const auto part = [&](std::size_t from, std::size_t n) {
    return std::vector<double>(dv.begin() + static_cast<long>(from),
                               dv.begin() + static_cast<long>(from + n));
  };
  k.parameters.push_back({"actuator_preset", part(9, 1), Range::any(), "",
                          "0: the axes given; 1 orthogonal, 2 pyramid, 3 nasa"});
  k.parameters.push_back(
      {"beta_deg", part(10, 1), Range::any(), "deg", "the pyramid wheels' elevation β"});
  k.parameters.push_back({"actuator_count", part(11, 1), Range::any(), "", "m"});
  k.parameters.push_back({"axes", part(12, 24), Range::any(), "", "each actuator's axis"});
  k.parameters.push_back({"max", part(36, 8), Range::any(), "N·m", "each actuator's limit"});
  k.parameters.push_back({"actuator_scale", part(44, 8), Range::non_negative(), "",
                          "each actuator's effectiveness in the simulated plant"});
  k.parameters.push_back({"actuator_misalignment", part(52, 8), Range::any(), "rad",
                          "the angle each actuator's true axis is turned by"});
  k.uncertain = {{"inertia", "each body axis of the inertia tensor (S J S)", Scaling::congruence},
                 {"actuator_scale", "each actuator's effectiveness", Scaling::elementwise, true},
                 {"actuator_misalignment", "the angle each actuator's axis is turned by",
                  Scaling::elementwise, true}};
  k.default_initial_state = {0.2, -0.15, 0.1, 0.0, 0.0, 0.0};
  k.positions = "attitude angles";
  k.rates = "Euler angle rates";
  k.axis_names = {"roll", "pitch", "yaw"};
  k.count_actuators = [](const std::vector<double>& v) {
    return actuator_count(rigid_body_spec(v));
  };
  k.check_values = [](const std::vector<double>& v, const std::string& path) {
    return validate(rigid_body_spec(v), path);
  };
  k.make = [](const std::vector<double>& v) -> std::unique_ptr<AnyPlant> {
    return std::make_unique<PlantAdapter<RigidBody>>(v, [](const std::vector<double>& w) {
      return RigidBody(rigid_body_params(rigid_body_spec(w)));
    });
  };
  return k;
}

PlantKind multirotor_kind() {
  PlantKind k;
  k.model = "multirotor";
  k.description =
      "a multirotor's attitude in hover with your inertia and 4 to 8 rotors in any layout or a "
      "preset (quad_x, quad_plus, hexa_x, octa_x); commands are thrust deviations from hover "
      "in N";
  k.axes = 3;
  k.actuators = kMaxBodyActuators;
  const MultirotorSpec d;
  const std::vector<double> dv = to_values(d);
  const auto part = [&](std::size_t from, std::size_t n) {
    return std::vector<double>(dv.begin() + static_cast<long>(from),
                               dv.begin() + static_cast<long>(from + n));
  };
  k.parameters = inertia_parameter(d.inertia);
  k.parameters.push_back({"mass", part(9, 1), Range::positive(), "kg", "mass m"});
  k.parameters.push_back({"gravity", part(10, 1), Range::positive(), "m/s²", "g"});
  k.parameters.push_back({"rotor_preset", part(11, 1), Range::any(), "",
                          "0: the rotors given; 1 quad_x, 2 quad_plus, 3 hexa_x, 4 octa_x"});
  k.parameters.push_back({"arm_length", part(12, 1), Range::any(), "m", "a preset's arm length"});
  k.parameters.push_back({"preset_max_thrust", part(13, 1), Range::any(), "N", "a preset's T_max"});
  k.parameters.push_back(
      {"preset_moment_constant", part(14, 1), Range::any(), "m", "a preset's κ"});
  k.parameters.push_back({"rotor_count", part(15, 1), Range::any(), "", "m"});
  k.parameters.push_back({"rotor_x", part(16, 8), Range::any(), "m", "each rotor's x"});
  k.parameters.push_back({"rotor_y", part(24, 8), Range::any(), "m", "each rotor's y"});
  k.parameters.push_back({"rotor_spin", part(32, 8), Range::any(), "", "+1 cw, -1 ccw"});
  k.parameters.push_back({"rotor_max_thrust", part(40, 8), Range::any(), "N", "each T_max"});
  k.parameters.push_back({"rotor_moment_constant", part(48, 8), Range::any(), "m", "each κ"});
  k.parameters.push_back({"actuator_scale", part(56, 8), Range::non_negative(), "",
                          "each rotor's effectiveness in the simulated plant"});
  k.uncertain = {{"inertia", "each body axis of the inertia tensor (S J S)", Scaling::congruence},
                 {"actuator_scale", "each rotor's effectiveness", Scaling::elementwise, true}};
  k.default_initial_state = {0.2, -0.15, 0.1, 0.0, 0.0, 0.0};
  k.positions = "attitude angles";
  k.rates = "angular rates";
  k.command_unit = "N";
  k.axis_names = {"roll", "pitch", "yaw"};
  k.count_actuators = [](const std::vector<double>& v) {
    return actuator_count(multirotor_spec(v));
  };
  k.check_values = [](const std::vector<double>& v, const std::string& path) {
    return validate(multirotor_spec(v), path);
  };
  k.make = [](const std::vector<double>& v) -> std::unique_ptr<AnyPlant> {
    return std::make_unique<PlantAdapter<RigidBody>>(v, [](const std::vector<double>& w) {
      return RigidBody(multirotor_params(multirotor_spec(w)));
    });
  };
  return k;
}

}  // namespace ftc::sim::detail
