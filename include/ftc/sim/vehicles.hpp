#pragma once
// Your vehicle as a job describes it (SPEC §17): the `rigid_body` plant (any inertia tensor, any
// actuator axes or a preset, a limit per actuator) and the `multirotor` plant (any rotor list or
// a preset layout), as option structs with their defaults, checked with every error at its JSON
// path, and turned into the RigidBody they describe (ftc/sim/rigid_body.hpp has the equations).
// The job reader (ftc/runtime/plant_json.hpp) reads and writes them; PlantSpec::values holds
// them flattened (to_values / *_spec).
#include <array>
#include <string>
#include <vector>

#include "ftc/sim/input_error.hpp"
#include "ftc/sim/rigid_body.hpp"

namespace ftc::sim {

// asin(1/√3) in degrees: each pyramid wheel equally inclined to the three body axes.
inline constexpr double kPyramidBetaDeg = 35.26438968275466;

struct RigidBodySpec {
  // J in kg·m², row-major; a job gives 3 principal moments or the 3×3 tensor.
  std::array<double, 9> inertia{0.25, 0.0, 0.0, 0.0, 0.30, 0.0, 0.0, 0.0, 0.20};
  // "orthogonal" (the body axes: 3 wheels), "pyramid" (4 wheels at azimuths 45° + 90°(j − 1),
  // elevation beta_deg), "nasa" (the body axes and (1, 1, 1)/√3), or "" for `axes`.
  std::string preset = "pyramid";
  double beta_deg = kPyramidBetaDeg;        // pyramid only
  std::vector<std::array<double, 3>> axes;  // without a preset: 3 to 8 axes (any length ≠ 0)
  std::vector<double> max;  // N·m, > 0: none (no limit), one for all, or one per actuator
  // How the simulated plant departs from this model (a scenario's keys, SPEC §17.1; the job's
  // plant, the controller's model, never has them): each actuator's effectiveness (its true
  // torque is actuator_scale_j · u_j along its true axis, ≥ 0) and the angle in rad by which its
  // true axis is turned (right-handedly about â_j × ẑ normalised, or â_j × x̂ when â_j is along
  // ẑ). Empty: 1 and 0 for every actuator; else one per actuator.
  std::vector<double> actuator_scale, actuator_misalignment;
};

struct RotorSpec {
  std::array<double, 2> position{0.0, 0.0};  // (x, y) in m, body frame, z up
  int spin = 1;                              // +1 clockwise ("cw"), −1 counter-clockwise ("ccw")
  double max_thrust = 8.0;                   // N
  double moment_constant = 0.016;            // m: N·m of drag torque per N of thrust
};

struct MultirotorSpec {
  double mass = 1.5;                                                                 // kg
  double gravity = 9.81;                                                             // m/s²
  std::array<double, 9> inertia{0.015, 0.0, 0.0, 0.0, 0.015, 0.0, 0.0, 0.0, 0.027};  // kg·m²
  // "quad_x" (rotors at 45° + 90°(i − 1)), "quad_plus" (0° + 90°(i − 1)), "hexa_x"
  // (30° + 60°(i − 1): the hexarotor's), "octa_x" (22.5° + 45°(i − 1)), odd rotors clockwise,
  // at arm_length with max_thrust and moment_constant; or "" for `rotors`.
  std::string preset = "quad_x";
  double arm_length = 0.25;        // m
  double max_thrust = 8.0;         // N
  double moment_constant = 0.016;  // m
  std::vector<RotorSpec> rotors;   // without a preset: 4 to 8 rotors
  // The simulated plant's effectiveness of each rotor (as RigidBodySpec's: a scenario's key,
  // never the model's): rotor i's torque per newton of commanded thrust deviation is
  // actuator_scale_i times the model's. Empty: 1 for every rotor; else one per rotor, ≥ 0.
  std::vector<double> actuator_scale;
};

// The preset names, for messages and the JSON Schema.
const std::vector<std::string>& body_presets();
const std::vector<std::string>& rotor_presets();

// Every error, at its path under `path` (/inertia/0/1, /actuators/axes/2, /rotors/3/max_thrust,
// ...): J not symmetric or not positive definite (saying which test failed), axes that are zero
// or do not span R³, limits that are not positive, a rotor layout that cannot make every torque
// or cannot hover inside its thrust limits.
std::vector<FieldError> inertia_errors(const std::array<double, 9>& J, const std::string& path);
std::vector<FieldError> validate(const RigidBodySpec& spec, const std::string& path);
std::vector<FieldError> validate(const MultirotorSpec& spec, const std::string& path);

// An actuator's true axis: the unit axis `a` turned by `angle` rad right-handedly about a × ẑ
// normalised (a × x̂ when |a × ẑ| < 1e-12), with ftctune's own sin and cos.
std::array<double, 3> misaligned_axis(const std::array<double, 3>& a, double angle);

// The actuator count: 3, 4 or the axes' number; the rotors'.
int actuator_count(const RigidBodySpec& spec);
int actuator_count(const MultirotorSpec& spec);

// The plant a valid spec describes (throws InputError for an invalid one).
RigidBodyParams rigid_body_params(const RigidBodySpec& spec);
RigidBodyParams multirotor_params(const MultirotorSpec& spec);
// The minimum-norm hover thrusts (A T = 0, Σ T = m g), one per rotor; exactly m g / n for a
// preset.
std::vector<double> hover_thrusts(const MultirotorSpec& spec);

// PlantSpec::values of each, and back.
std::vector<double> to_values(const RigidBodySpec& spec);
std::vector<double> to_values(const MultirotorSpec& spec);
RigidBodySpec rigid_body_spec(const std::vector<double>& values);
MultirotorSpec multirotor_spec(const std::vector<double>& values);

}  // namespace ftc::sim
