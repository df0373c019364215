#pragma once
// Plants by name, as job files know them. Each registered plant describes its parameters (name,
// default, valid range, unit) and builds an AnyPlant: the plant with the simulator and the four
// controllers compiled for its shape, behind one dimension-free interface. This is the seam the
// tuner uses; it never sees n or m as types.
//
// Shipped: "spacecraft" (n = 3, m = 4; the paper's plant), "manipulator" (a planar two-link
// arm, n = 2, m = 3) and "hexarotor" (attitude in hover, n = 3, m = 6). To add one, see
// docs/architecture.md ("Plant seam").
#include <functional>
#include <limits>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "ftc/sim/controller_config.hpp"
#include "ftc/sim/input_error.hpp"
#include "ftc/sim/isa.hpp"
#include "ftc/sim/range.hpp"
#include "ftc/sim/scenario.hpp"
#include "ftc/sim/simulation.hpp"

namespace ftc::sim {

// One named parameter of a plant: a number (one default) or a fixed-length array.
struct PlantParameter {
  std::string name;
  std::vector<double> defaults;
  Range range;  // of each value
  std::string unit;
  std::string description;

  std::size_t size() const { return defaults.size(); }
};

// How an ensemble's factors act on an uncertain parameter's values.
enum class Scaling : std::uint8_t {
  elementwise,  // value i times factor i (a diagonal inertia: one factor per axis)
  congruence,   // a 3×3 tensor J (row-major) to S J S, S = diag(√s_i): factor i scales axis i
};

// A parameter a plant declares uncertain, in its own PlantKind. A scenario may give the
// simulated plant's true values of it under the parameter's name (model mismatch: the controller
// keeps the job's values as its model), and an ensemble scales it member by member under the
// key `<parameter>_scale`. No other parameter can be given either way.
struct UncertainParameter {
  std::string parameter;  // the name of one of the kind's PlantParameters
  std::string meaning;    // what the scale acts on, in words ("each axis's principal moment")
  Scaling scaling = Scaling::elementwise;
  // One value per actuator (SPEC §17's actuator_scale and actuator_misalignment): a scenario
  // gives the plant's m of them (the kind's parameter holds kMaxActuators), and an ensemble
  // draws them under the parameter's own name, one per actuator after SPEC §12's draws, instead
  // of scaling them with the 3 factors.
  bool per_actuator = false;
  // At most this many values: the ensemble draws that many factors (SPEC §12's 3).
  static constexpr std::size_t kMaxFactors = 3;
};

// A plant as a file gives it: its model name and the values of its parameters, flattened in
// the order of its PlantKind's parameters.
struct PlantSpec {
  std::string model = "spacecraft";
  std::vector<double> values;  // empty: the defaults
};

class AnyPlant;

// One simulation of a batch: a controller on a scenario with its options.
struct PackTask {
  const ControllerConfig* controller = nullptr;
  const Scenario* scenario = nullptr;
  const SimulationOptions* options = nullptr;
};

struct PlantKind {
  std::string model;
  std::string description;
  int axes = 0;       // n
  int actuators = 0;  // m; for a kind whose count its values give, the most it allows
  // A kind whose actuator count depends on its values (rigid_body, multirotor): that count.
  std::function<int(const std::vector<double>& values)> count_actuators;
  // A kind whose values are checked as a whole (their JSON paths are not those of the flattened
  // parameters): every error, named under `path`. Replaces the per-value range checks.
  std::function<std::vector<FieldError>(const std::vector<double>& values,
                                        const std::string& path)>
      check_values;

  std::vector<PlantParameter> parameters;
  std::vector<UncertainParameter> uncertain;  // of `parameters`; none: no mismatch, no scaling
  std::vector<double> default_initial_state;  // 2n values, for scenarios that give none
  // For figures and tables: what X1 and X2 are, per axis, and their units.
  std::string positions = "positions";  // "attitude angles"
  std::string rates = "rates";          // "angular rates"
  std::vector<std::string> axis_names;  // n names: "roll", "pitch", "yaw"
  std::string position_unit = "rad";
  std::string rate_unit = "rad/s";
  std::string command_unit = "N·m";  // of a command u_j: "N" for rotor thrusts
  // Builds the plant from validated values (the flattened parameters).
  std::function<std::unique_ptr<AnyPlant>(const std::vector<double>& values)> make;

  std::vector<double> defaults() const;
  // m for these values (the defaults when empty).
  int actuators_of(const std::vector<double>& values) const;
  std::size_t value_count() const;
  // Index of a parameter's first value in the flattened values; npos when unknown.
  std::size_t offset(std::string_view parameter) const;
  // Every value out of its parameter's range, named `path`/<parameter>[/<index>].
  std::vector<FieldError> validate(const std::vector<double>& values,
                                   const std::string& path) const;
  // The declaration of an uncertain parameter; null when `parameter` is not one.
  const UncertainParameter* find_uncertain(std::string_view parameter) const;
  // The names of the uncertain parameters, comma-separated, or "none".
  std::string uncertain_names() const;
  // The values of one parameter (which must exist).
  std::vector<double> parameter_values(const std::vector<double>& values,
                                       std::string_view parameter) const;
  // The values with a scenario's true values put in place of the parameters they name; checks
  // that each is an uncertain parameter of this plant with the right number of values, naming
  // `path`/<parameter> otherwise.
  std::vector<double> with_true_values(std::vector<double> values,
                                       const std::vector<TrueValue>& truth,
                                       const std::string& path) const;
  // Every error of a scenario's true values against this plant (with_true_values' and the
  // ranges of the values it gives), named `path`/<parameter>[/<index>].
  std::vector<FieldError> check_true_values(const std::vector<double>& values,
                                            const std::vector<TrueValue>& truth,
                                            const std::string& path) const;
  // `values` (a parameter's) scaled by `factors` by the parameter's rule.
  static void scale(const UncertainParameter& u, std::vector<double>& values,
                    std::span<const double> factors);
};

// A plant of any shape with the simulator and controllers compiled for it. Immutable and
// thread-safe: any number of threads may simulate on one AnyPlant at once.
class AnyPlant {
 public:
  virtual ~AnyPlant() = default;
  virtual const PlantKind& kind() const = 0;
  int axes() const { return kind().axes; }
  // m: this plant's actuators (a kind with a variable count: its spec's, PlantKind::actuators_of).
  virtual int actuators() const { return kind().actuators; }

  // One scenario with a fresh controller of the given configuration. The controller is given
  // this plant as its model; the simulated plant is the same unless the scenario names a true
  // inertia. Throws InputError for an invalid controller or scenario; a diverging run is a
  // result, never an exception.
  virtual SimulationResult simulate(const ControllerConfig& controller, const Scenario& scenario,
                                    const SimulationOptions& options = {}) const = 0;

  // Many simulations, each with exactly the result simulate() gives it (to the last bit), in
  // SIMD lanes of the plant's batch kernel (see ftc/sim/isa.hpp; every registered plant has
  // one), one after another otherwise. results[i] and errors[i] belong to tasks[i]; a task whose
  // controller or scenario is invalid gets the InputError's message in errors[i] instead of a
  // result. Never throws for a task's sake.
  virtual void simulate_pack(std::span<const PackTask> tasks, std::span<SimulationResult> results,
                             std::span<std::string> errors) const;
  // The same on a given instruction set (one of supported_isas()): the results do not depend on
  // it (tests and benchmarks compare them).
  virtual void simulate_pack(std::span<const PackTask> tasks, std::span<SimulationResult> results,
                             std::span<std::string> errors, Isa isa) const;
  // How many simulations simulate_pack runs in lockstep (1 without a batch kernel); a caller
  // that hands it that many compatible tasks at a time (same sample time, substeps, duration,
  // controller type) keeps every lane busy.
  virtual int pack_width() const { return 1; }

  // Whether any gains can control every axis once all of the scenario's faults have started:
  // the actuators still acting (not stuck, not wholly lost) leave G, at the scenario's initial
  // state, with full row rank n.
  virtual bool recoverable(const Scenario& scenario) const = 0;

  // Each actuator's range of commands in the scenario, [lo, hi] in the command's coordinates
  // (the deviation from the operating point for a plant with one): the plant's own range within
  // ± the scenario's saturation, as the loop limits them (±inf: no limit). For figures.
  virtual std::vector<std::pair<double, double>> command_limits(const Scenario& scenario) const = 0;
};

const std::vector<PlantKind>& plant_kinds();
// nullptr when no plant has that model name.
const PlantKind* find_plant_kind(std::string_view model);
// "spacecraft, manipulator": for messages.
std::string plant_model_names();
// Builds the plant of a spec; throws InputError (source "plant") for an unknown model or bad
// values.
std::unique_ptr<AnyPlant> make_plant(const PlantSpec& spec);

}  // namespace ftc::sim
