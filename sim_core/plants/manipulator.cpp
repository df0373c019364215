#include "ftc/sim/manipulator.hpp"

#include <array>
#include <memory>
#include <string>
#include <vector>

#include "checks.hpp"
#include "plants/kinds.hpp"
#include "plants/manipulator_dynamics.hpp"
#include "plants/plant_adapter.hpp"

namespace ftc::sim {

Manipulator::Manipulator(const ManipulatorParams& params) : params_(params) {
  std::vector<FieldError> errs;
  // In the order of the parameters in a job file, so that errors are listed as they appear.
  const auto check_pair = [&](const char* name, const std::array<double, 2>& v) {
    for (int i = 0; i < 2; ++i)
      detail::check_positive(errs, std::string("/") + name + "/" + std::to_string(i), v[i]);
  };
  check_pair("masses", params.masses);
  check_pair("lengths", params.lengths);
  check_pair("centres_of_mass", params.centres_of_mass);
  check_pair("inertias", params.inertias);
  detail::check_non_negative(errs, "/gravity", params.gravity);
  throw_if_errors("plant", std::move(errs));

  const double m1 = params.masses[0], m2 = params.masses[1];
  const double l1 = params.lengths[0];
  const double lc1 = params.centres_of_mass[0], lc2 = params.centres_of_mass[1];
  const double I1 = params.inertias[0], I2 = params.inertias[1];
  const double g0 = params.gravity;
  a1_ = m1 * lc1 * lc1 + m2 * (l1 * l1 + lc2 * lc2) + I1 + I2;
  a2_ = m2 * l1 * lc2;
  a3_ = m2 * lc2 * lc2 + I2;
  b1_ = (m1 * lc1 + m2 * l1) * g0;
  b2_ = m2 * lc2 * g0;
}

Manipulator::Vector Manipulator::f(const State& x) const {
  double s1, c1, s2, c2;
  math::sincos(x[0], s1, c1);
  math::sincos(x[1], s2, c2);
  double out[2];
  arm_f<double>(a2_, b1_, b2_, arm_inverse_mass<double>(a1_, a2_, a3_, c2), s1, c1, s2, c2, x[2],
                x[3], out);
  return Vector(out[0], out[1]);
}

Manipulator::InputMatrix Manipulator::G(const State& x) const {
  const ArmInverseMass<double> Mi = arm_inverse_mass<double>(a1_, a2_, a3_, math::cos(x[1]));
  InputMatrix g;
  g << Mi.d11, Mi.d12, Mi.d11 + Mi.d12,  //
      Mi.d12, Mi.d22, Mi.d12 + Mi.d22;
  return g;
}

double Manipulator::energy(const State& x) const {
  const Vector q = x.head<2>(), qd = x.tail<2>();
  const double kinetic = 0.5 * qd.dot(mass_matrix(q) * qd);
  const double potential = b1_ * math::sin(q[0]) + b2_ * math::sin(q[0] + q[1]);
  return kinetic + potential;
}

Manipulator::InputMatrix Manipulator::actuator_matrix() {
  InputMatrix b;
  b << 1.0, 0.0, 1.0,  //
      0.0, 1.0, 1.0;
  return b;
}

Manipulator::InputInverse Manipulator::actuator_pinv() {
  InputInverse p;
  p << 2.0, -1.0,  //
      -1.0, 2.0,   //
      1.0, 1.0;
  return p / 3.0;
}

}  // namespace ftc::sim

namespace ftc::sim::detail {

PlantKind manipulator_kind() {
  PlantKind k;
  k.model = "manipulator";
  k.description =
      "planar two-link robot arm in a vertical plane, 2 joints, 3 actuators (one motor per "
      "joint and a biarticular one driving both)";
  k.axes = 2;
  k.actuators = 3;
  const ManipulatorParams d;
  const auto both = [](const std::array<double, 2>& a) { return std::vector<double>{a[0], a[1]}; };
  const Range positive = Range::positive();
  k.parameters = {
      {"masses", both(d.masses), positive, "kg", "link masses m1, m2"},
      {"lengths", both(d.lengths), positive, "m", "link lengths l1, l2"},
      {"centres_of_mass", both(d.centres_of_mass), positive, "m",
       "distances lc1, lc2 from joint i to the centre of mass of link i"},
      {"inertias", both(d.inertias), positive, "kg·m²",
       "moments of inertia I1, I2 of the links about their centres of mass"},
      {"gravity", {d.gravity}, Range::non_negative(), "m/s²", "gravitational acceleration g0"}};
  k.default_initial_state = {0.5, -0.4, 0.0, 0.0};
  k.positions = "joint angles";
  k.rates = "joint rates";
  k.axis_names = {"q1", "q2"};
  k.make = [](const std::vector<double>& v) -> std::unique_ptr<AnyPlant> {
    return std::make_unique<PlantAdapter<Manipulator>>(v, [](const std::vector<double>& w) {
      ManipulatorParams p;
      p.masses = {w.at(0), w.at(1)};
      p.lengths = {w.at(2), w.at(3)};
      p.centres_of_mass = {w.at(4), w.at(5)};
      p.inertias = {w.at(6), w.at(7)};
      p.gravity = w.at(8);
      return Manipulator(p);
    });
  };
  return k;
}

}  // namespace ftc::sim::detail
