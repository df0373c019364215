#pragma once
// One closed-loop fault scenario: run length, sampling, initial state, disturbance and faults.
#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "ftc/sim/disturbance.hpp"
#include "ftc/sim/faults.hpp"
#include "ftc/sim/fields.hpp"
#include "ftc/sim/input_error.hpp"
#include "ftc/sim/sensors.hpp"

namespace ftc::sim {

// A scenario's true values of one uncertain plant parameter (model mismatch).
struct TrueValue {
  std::string parameter;  // the name of a parameter its plant declares uncertain
  std::vector<double> values;
};

// The dynamics of a plant's actuators (docs/model.md "Actuator dynamics"): each actuator's output
// u_a follows its command, clamped to the actuator's range, with a first-order lag τ and a rate
// limit R; faults and saturation then act on u_a. At least one of the two is given; a scenario
// without a model drives the plant with the command itself.
struct ActuatorModel {
  std::optional<double> time_constant;  // τ in s; absent: no lag
  std::optional<double> rate_limit;     // R in units of u per s; absent: no limit
  static constexpr Range kTimeConstantRange = Range::positive();
  static constexpr Range kRateLimitRange = Range::positive();
  static constexpr double kMinSteps = 2.0;  // τ ≥ 2 h, h = Ts / substeps
};

// The model's update over one half step h/2 of RK4 (the instants the plant's inputs are taken
// at): u_a ← u_a + clamp((u_c − u_a)·gain, −max_step, max_step), gain = 1 − exp(−h/(2τ)) (1
// without a lag), max_step = R·h/2 (+inf without a limit). Computed once per run, so the loops
// (the kernel's and the Controller's) share the bits.
struct ActuatorSteps {
  double gain = 1.0;
  double max_step = std::numeric_limits<double>::infinity();
};
ActuatorSteps actuator_steps(const ActuatorModel& model, double half_step);

struct Scenario {
  std::string name = "paper";
  double duration = 30.0;     // T in s, a whole number of sample times
  double sample_time = 1e-3;  // Ts in s: controller period and zero-order hold
  int substeps = 1;           // RK4 steps per sample, h = Ts / substeps
  // X(0) = (X1, X2), 2n values. Empty here: a job fills in its plant's default when it gives
  // none (paper() sets the paper's spacecraft state); simulate() needs all 2n.
  std::vector<double> initial_state;
  std::vector<DisturbanceTerm> disturbance;
  std::vector<Fault> faults;
  // |u_j| ≤ the actuator's limit, before and after the faults (ftc/sim/faults.hpp): one for every
  // actuator or one per actuator; none = no limit but the plant's own.
  Saturation saturation;
  std::optional<ActuatorModel> actuator;  // absent: the command drives the plant directly
  // What the controller reads (ftc/sim/sensors.hpp, SPEC §18); absent: the exact state and
  // acceleration.
  std::optional<SensorModel> sensors;
  // The true values of plant parameters the plant declares uncertain (PlantKind::uncertain),
  // when the simulated plant differs from the model the controller is given (model mismatch);
  // empty = the plant's own. Each overrides the plant parameter it names.
  std::vector<TrueValue> true_values;

  // The true values of one parameter; null when the scenario gives none.
  const std::vector<double>* true_value(std::string_view parameter) const;
  // The sensors the controller reads through; null when it reads the exact state and
  // acceleration (no block, or one whose measurements are exact: SensorModel::exact), whose loop
  // is the loop without sensors, bit for bit.
  const SensorModel* active_sensors() const {
    return sensors && !sensors->exact() ? &*sensors : nullptr;
  }
  // Sets (or replaces) the true values of one parameter.
  void set_true_value(const std::string& parameter, std::vector<double> values);

  // N = round(T / Ts).
  std::int64_t samples() const { return std::llround(duration / sample_time); }
  // Every bad field, for a plant with `axes` (n) and `actuators` (m).
  std::vector<FieldError> validate(const std::string& path, int axes, int actuators) const;

  // The numeric fields (duration, sample_time) and the substeps, as tables.
  static std::span<const NumberField<Scenario>> number_fields();
  static const IntegerField<Scenario>& substeps_field();
  static constexpr Range kSaturationRange = Range::positive();

  // The paper's scenario (§6): Δ = 0.5 [sin t, cos 2t, sin 3t], bias 5 + 15 cos t on actuator
  // 1 from 10 s, 80 % loss of effectiveness on actuator 2 from 20 s.
  static Scenario paper();
};

}  // namespace ftc::sim
