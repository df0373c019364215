#include "ftc/sim/hexarotor.hpp"

#include <Eigen/LU>
#include <algorithm>
#include <array>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "checks.hpp"
#include "plants/hexarotor_dynamics.hpp"
#include "plants/hover.hpp"
#include "plants/kinds.hpp"
#include "plants/plant_adapter.hpp"

namespace ftc::sim {

Hexarotor::Hexarotor(const HexarotorParams& params) : params_(params) {
  std::vector<FieldError> errs;
  // In the order of the parameters in a job file, so that errors are listed as they appear.
  for (int i = 0; i < 3; ++i)
    detail::check_positive(errs, "/inertia/" + std::to_string(i), params.inertia[i]);
  detail::check_positive(errs, "/mass", params.mass);
  detail::check_positive(errs, "/arm_length", params.arm_length);
  detail::check_positive(errs, "/max_thrust", params.max_thrust);
  detail::check_positive(errs, "/moment_constant", params.moment_constant);
  detail::check_positive(errs, "/gravity", params.gravity);
  if (errs.empty() && !(6.0 * params.max_thrust > params.mass * params.gravity))
    errs.push_back({"/max_thrust", "six rotors at " + std::to_string(params.max_thrust) +
                                       " N cannot carry the weight m g = " +
                                       std::to_string(params.mass * params.gravity) + " N"});
  throw_if_errors("plant", std::move(errs));

  const double Ix = params.inertia[0], Iy = params.inertia[1], Iz = params.inertia[2];
  kx_ = (Iy - Iz) / Ix;
  ky_ = (Iz - Ix) / Iy;
  kz_ = (Ix - Iy) / Iz;
  hover_ = params.mass * params.gravity / 6.0;
  double G[18], Gp[18];
  const double I[3] = {Ix, Iy, Iz};
  hexarotor_input<double>(I, params.arm_length, params.moment_constant, G, Gp);
  for (int k = 0; k < 3; ++k)
    for (int i = 0; i < 6; ++i) {
      G_(k, i) = G[k * 6 + i];
      G_pinv_(i, k) = Gp[i * 3 + k];
    }
}

Hexarotor::Vector Hexarotor::f(const State& x) const {
  double out[3];
  hexarotor_f<double>(kx_, ky_, kz_, x[3], x[4], x[5], out);
  return Vector(out[0], out[1], out[2]);
}

std::array<double, 5> Hexarotor::f_constants() const {
  return {params_.inertia[0], params_.inertia[1], params_.inertia[2], params_.arm_length,
          params_.moment_constant};
}

Hexarotor::Trim Hexarotor::actuator_trim() const {
  Trim t;
  t.u0.fill(hover_);
  t.lo.fill(-hover_);
  t.hi.fill(params_.max_thrust - hover_);
  return t;
}

Hexarotor::InputMatrix Hexarotor::torque_matrix() const {
  InputMatrix A;
  for (int k = 0; k < 3; ++k)
    for (int i = 0; i < 6; ++i)
      A(k, i) = hexarotor_torque<double>(k, i, params_.arm_length, params_.moment_constant);
  return A;
}

Hexarotor::ThrustRange Hexarotor::thrust_range() const {
  ThrustRange r;
  r.floor.fill(0.0);
  r.cap.fill(params_.max_thrust);
  return r;
}

double Hexarotor::trim_margin(const std::array<bool, 6>& stuck,
                              const std::array<double, 6>& stuck_at,
                              const std::array<double, 6>& lost, const ThrustRange& range) const {
  const InputMatrix A = torque_matrix();
  return detail::hold_margin(A, params_.mass * params_.gravity, stuck, stuck_at, lost,
                              range.floor, range.cap, params_.max_thrust);
}

bool Hexarotor::trim_feasible(const std::array<bool, 6>& stuck,
                              const std::array<double, 6>& stuck_at,
                              const std::array<double, 6>& lost, const ThrustRange& range) const {
  return trim_margin(stuck, stuck_at, lost, range) > 1e-9 * params_.max_thrust;
}

}  // namespace ftc::sim

namespace ftc::sim::detail {

PlantKind hexarotor_kind() {
  PlantKind k;
  k.model = "hexarotor";
  k.description =
      "hexarotor attitude (roll, pitch, yaw) in hover, 6 rotors in the standard hexagonal "
      "layout; commands are thrust deviations from hover";
  k.axes = 3;
  k.actuators = 6;
  const HexarotorParams d;
  const Range positive = Range::positive();
  k.parameters = {
      {"inertia", {d.inertia[0], d.inertia[1], d.inertia[2]}, positive, "kg·m²",
       "principal moments of inertia Ix, Iy, Iz"},
      {"mass", {d.mass}, positive, "kg", "mass m (sets the hover thrust m g / 6 per rotor)"},
      {"arm_length", {d.arm_length}, positive, "m", "distance l from the centre to each rotor"},
      {"max_thrust", {d.max_thrust}, positive, "N", "largest thrust T_max of one rotor"},
      {"moment_constant", {d.moment_constant}, positive, "m",
       "yaw (drag) torque per newton of a rotor's thrust"},
      {"gravity", {d.gravity}, positive, "m/s²", "gravitational acceleration g"}};
  k.uncertain = {{"inertia", "each axis's principal moment of inertia", Scaling::elementwise}};
  k.default_initial_state = {0.2, -0.15, 0.1, 0.0, 0.0, 0.0};
  k.positions = "attitude angles";
  k.rates = "angular rates";
  k.command_unit = "N";
  k.axis_names = {"roll", "pitch", "yaw"};
  k.make = [](const std::vector<double>& v) -> std::unique_ptr<AnyPlant> {
    return std::make_unique<PlantAdapter<Hexarotor>>(v, [](const std::vector<double>& w) {
      HexarotorParams p;
      p.inertia = {w.at(0), w.at(1), w.at(2)};
      p.mass = w.at(3);
      p.arm_length = w.at(4);
      p.max_thrust = w.at(5);
      p.moment_constant = w.at(6);
      p.gravity = w.at(7);
      return Hexarotor(p);
    });
  };
  return k;
}

}  // namespace ftc::sim::detail
