#include "ftc/sim/spacecraft.hpp"

#include <Eigen/LU>
#include <cmath>
#include <memory>
#include <vector>

#include "checks.hpp"
#include "ftc/sim/elementary.hpp"
#include "plants/kinds.hpp"
#include "plants/plant_adapter.hpp"
#include "plants/spacecraft_dynamics.hpp"

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
  G_pinv_ = right_inverse(G_);
}

Vec3 Spacecraft::f(const State& x) const {
  double s[3], c[3];
  for (int i = 0; i < 3; ++i) {
    math::sincos(x[i], s[i], c[i]);
  }
  return f_trig(x, s, c);
}

}  // namespace ftc::sim

namespace ftc::sim {

SpacecraftParams spacecraft_params(const PlantSpec& spec) {
  if (spec.model != "spacecraft")
    throw InputError("plant", "/model", "is \"" + spec.model + "\", expected \"spacecraft\"");
  const PlantKind& kind = *find_plant_kind("spacecraft");
  const std::vector<double> v = spec.values.empty() ? kind.defaults() : spec.values;
  throw_if_errors("plant", kind.validate(v, ""));
  SpacecraftParams p;
  const std::size_t inertia = kind.offset("inertia"), rate = kind.offset("orbital_rate");
  p.inertia = {v[inertia], v[inertia + 1], v[inertia + 2]};
  p.orbital_rate = v[rate];
  return p;
}

}  // namespace ftc::sim

namespace ftc::sim::detail {

PlantKind spacecraft_kind() {
  PlantKind k;
  k.model = "spacecraft";
  k.description =
      "rigid spacecraft attitude in Euler angles on a circular orbit, 3 axes, 4 actuators "
      "(paper §6, Appendix B)";
  k.axes = 3;
  k.actuators = 4;
  const SpacecraftParams d;
  k.parameters = {
      {"inertia",
       {d.inertia[0], d.inertia[1], d.inertia[2]},
       Range::positive(),
       "kg·m²",
       "principal moments of inertia Ix, Iy, Iz"},
      {"orbital_rate", {d.orbital_rate}, Range::non_negative(), "rad/s", "orbital rate ω0"}};
  // A scenario may give the true inertia (SPEC §12); an ensemble scales each axis's moment.
  k.uncertain = {{"inertia", "each axis's principal moment of inertia", Scaling::elementwise}};
  k.default_initial_state = {-0.7, -0.07, 1.5, 0.3, 1.3, -0.2};
  k.positions = "attitude angles";
  k.rates = "angular rates";
  k.axis_names = {"roll", "pitch", "yaw"};
  k.make = [](const std::vector<double>& v) -> std::unique_ptr<AnyPlant> {
    return std::make_unique<PlantAdapter<Spacecraft>>(v, [](const std::vector<double>& values) {
      return Spacecraft(spacecraft_params(PlantSpec{"spacecraft", values}));
    });
  };
  return k;
}

}  // namespace ftc::sim::detail
