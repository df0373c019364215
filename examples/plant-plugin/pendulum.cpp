// The pendulum's parameters, its constants, and the plugin's entry point.
#include "pendulum.hpp"

#include <vector>

#include "ftc/sim/input_error.hpp"
#include "plants/plugin_entry.hpp"

namespace pendulum {

Pendulum::Pendulum(const Params& p) {
  std::vector<ftc::FieldError> errs;
  if (!(p.inertia > 0)) errs.push_back({"/inertia", "must be positive"});
  if (!(p.friction >= 0)) errs.push_back({"/friction", "must not be negative"});
  for (int j = 0; j < 2; ++j)
    if (!(p.wheel_gains[j] >= 0))
      errs.push_back({"/wheel_gains/" + std::to_string(j), "must not be negative"});
  ftc::throw_if_errors("plant", std::move(errs));
  a_ = p.mass_length * p.gravity / p.inertia;
  c_ = p.friction / p.inertia;
  g1_ = -p.wheel_gains[0] / p.inertia;
  g2_ = -p.wheel_gains[1] / p.inertia;
}

// The plant as job files know it. The parameters' order is the order of the values build()
// reads.
ftc::sim::PlantKind kind() {
  using ftc::Range;
  ftc::sim::PlantKind k;
  k.model = "plugin:reaction_wheel_pendulum";
  k.description = "reaction-wheel inverted pendulum, 1 axis, 2 wheels (examples/plant-plugin)";
  k.axes = 1;
  k.actuators = 2;
  const Params d;
  k.parameters = {
      {"inertia",
       {d.inertia},
       Range::positive(),
       "kg·m²",
       "moment of inertia J of the pendulum about its pivot, wheels included"},
      {"mass_length",
       {d.mass_length},
       Range::non_negative(),
       "kg·m",
       "mass times the distance from the pivot to the centre of mass, m ℓ"},
      {"gravity", {d.gravity}, Range::non_negative(), "m/s²", "gravitational acceleration g0"},
      {"friction",
       {d.friction},
       Range::non_negative(),
       "N·m·s/rad",
       "viscous friction b of the pivot"},
      {"wheel_gains",
       {d.wheel_gains[0], d.wheel_gains[1]},
       Range::non_negative(),
       "",
       "k_1, k_2: the share of the commanded torque each wheel's motor gives"}};
  k.uncertain = {{"inertia", "the pendulum's moment of inertia J"},
                 {"mass_length", "the pendulum's unbalance m ℓ"}};
  k.default_initial_state = {0.1, 0.0};
  k.positions = "angle from upright";
  k.rates = "angular rate";
  k.axis_names = {"theta"};
  k.command_unit = "N·m";
  return k;
}

Pendulum build(const std::vector<double>& v) {
  Params p;
  p.inertia = v.at(0);
  p.mass_length = v.at(1);
  p.gravity = v.at(2);
  p.friction = v.at(3);
  p.wheel_gains = {v.at(4), v.at(5)};
  return Pendulum(p);
}

}  // namespace pendulum

#ifndef PENDULUM_COMPILED_IN
FTCTUNE_PLANT_PLUGIN(pendulum::Pendulum, pendulum::kind, pendulum::build)
#endif
