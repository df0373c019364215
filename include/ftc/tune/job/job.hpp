#pragma once
// The tuning job file `ftctune.job/1`: plant, fault scenarios, controller, objective and
// tuning settings. load_job() is strict: unknown keys, wrong types and out-of-range values are
// reported together, each with its JSON path, in one InputError.
#include <cstdint>
#include <filesystem>
#include <memory>
#include <nlohmann/json_fwd.hpp>
#include <optional>
#include <string>
#include <vector>

#include "ftc/runtime/controller_json.hpp"
#include "ftc/runtime/json_reader.hpp"
#include "ftc/runtime/scenario_json.hpp"
#include "ftc/sim/controller_config.hpp"
#include "ftc/sim/input_error.hpp"
#include "ftc/sim/metrics_record.hpp"
#include "ftc/sim/plants.hpp"
#include "ftc/sim/scenario.hpp"
#include "ftc/tune/optimizers/optimizer.hpp"

namespace ftc::tune {

inline constexpr const char* kJobSchema = "ftctune.job/1";
inline constexpr const char* kScenariosSchema = "ftctune.scenarios/1";
// The most errors `validate` and the service list for one input; the rest are counted ("and N
// more"), so that a file of 10^5 broken entries gives an answer of kilobytes, not megabytes.
inline constexpr std::size_t kMaxReportedErrors = 100;

using runtime::parse_controller;
using runtime::to_json;

// The plant of a job: its model name and parameter values (sim_core's plant registry describes
// them); the loader fills in every default.
using PlantConfig = sim::PlantSpec;

// How the scenarios' values combine into the objective (SPEC §13): for n values sorted
// ascending, quantile is the nearest rank v_ceil(q n), cvar the mean of the largest
// ceil((1 - alpha) n); a diverged scenario counts +inf.
enum class Aggregate { mean, max, quantile, cvar };
const char* to_string(Aggregate a);

// Where the objective window is measured from: each run's start, or each scenario's earliest
// fault onset (so members with random onsets are all scored on their recovery).
enum class WindowFrom { start, first_fault };

// A metric of the job: a field of the metrics record, the table every property of it comes from
// (its scope, unit, label, whether it can be a goal or the objective, ...). Never null.
using MetricRef = const sim::MetricField*;

struct ObjectiveConfig {
  // A field marked `objective` (a window field).
  MetricRef metric = &sim::kMetricFields[sim::metric_index("ise")];
  sim::Window window;  // default: the whole run
  Aggregate aggregate = Aggregate::mean;
  double q = 0.9;      // quantile
  double alpha = 0.9;  // cvar
  WindowFrom window_from = WindowFrom::start;

  // The window of one scenario: the job's window, shifted to the scenario's first fault when
  // window_from is first_fault, and cut at the scenario's end.
  sim::Window window_of(const sim::Scenario& s) const;
  // The aggregate of values (+inf for a diverged run); 0 values give 0.
  double aggregate_of(std::vector<double> values) const;
  // The metric's value on one run, in its objective window (+inf for a diverged run).
  double value(const sim::Metrics& m) const { return m.errors.*metric->in_window; }
};

// What two of the window metrics are measured against (ftc/sim/metrics.hpp): a job without
// them has no settling time and no steady-state error (NaN in its documents).
struct MetricsConfig {
  std::optional<double> settling_threshold;  // rad: ‖e‖ below it counts as settled
  std::optional<double> steady_state_tail;   // s: the steady-state error's tail of each window
  // The outcome checks of a run (tuning_run.hpp's comparison_warnings), when not their defaults:
  // a tuned loop that ends farther from the reference than it started and than drift_warning
  // (the plant's position unit), and tuned gains whose control TV exceeds control_tv_warning
  // times the job's own gains', are warned of.
  std::optional<double> drift_warning;       // default kDriftWarningFloor
  std::optional<double> control_tv_warning;  // default kControlTvWarningRatio
};

// A goal of the job (issue 26): a metric in a window, aggregated over the scenarios as the
// objective's are, either minimised (a soft goal) or kept at most a limit (a hard goal, its
// normalised violation max(0, value/at_most - 1)). A job gives "objective" or "goals".
struct GoalConfig {
  // A field marked `goal`; measured in the window when its scope is a window, else over the whole
  // run.
  MetricRef metric = &sim::kMetricFields[sim::metric_index("ise")];
  sim::Window window;  // default: the whole run
  WindowFrom window_from = WindowFrom::start;
  Aggregate aggregate = Aggregate::mean;
  double q = 0.9;
  double alpha = 0.9;
  bool minimize = false;          // a soft goal
  std::optional<double> at_most;  // a hard goal's limit, > 0
  // The settings of a metric measured against one (MetricField::setting): the settling
  // threshold, rad, and the steady-state tail, s (else the job's metrics block's).
  std::optional<double> threshold;
  std::optional<double> tail;

  bool soft() const { return minimize; }
  // Whether it is measured in a window (a window field), not over the whole run.
  bool windowed() const { return metric->scope == sim::MetricScope::window; }
  // The goal's window and aggregate as an objective's (its metric field is left at ise).
  ObjectiveConfig measure() const;
  // The normalised violation max(0, value/at_most - 1) of a hard goal (0 for a soft one); a
  // NaN or +inf value violates by +inf.
  double violation(double value) const;
};

enum class Scale { linear, log };

struct ParameterBounds {
  std::string name;  // a tunable field of the controller
  double lower = 0.0;
  double upper = 0.0;
  Scale scale = Scale::linear;  // log: the optimiser searches ln x uniformly (0 < lower)
};

// Where a front's noise floor (SPEC §14's R nudged reruns) is measured: at every point of the
// front, or at the picked point only (R × scenarios simulations instead of R × points ×
// scenarios, for fronts over large ensembles; the other points' floors are then unknown).
enum class FrontNoiseFloor { every_point, picked };

struct TuningConfig {
  std::vector<ParameterBounds> parameters;
  AlgorithmPtr algorithm = default_algorithm();  // the Bat algorithm with Table 1 settings
  std::uint64_t seed = 1;
  FrontNoiseFloor noise_floor = FrontNoiseFloor::every_point;

  static AlgorithmPtr default_algorithm();
};

struct CompareEntry {
  std::string label;  // shown in comparisons; defaults to the controller type
  sim::ControllerConfig controller;
};

struct EnsembleConfig;  // job/ensemble.hpp

// The cost of one fault at one simulated step, in fault-free steps: measured with
// `ftctune run` of a 60 s, 1 ms table1 scenario, 16 bats, 2 iterations, on a 2-core AMD EPYC:
// 0.40 s without faults, 2.5 s with 200 bias faults and 9.0 s with 1 000 (6.2 and 22 times:
// 1/38 and 1/47 of a step per fault, their onsets spread over the first half; one from the start
// costs about 1/32).
inline constexpr double kFaultStepCost = 1.0 / 32.0;

struct Job {
  std::string name;
  PlantConfig plant;
  std::vector<sim::Scenario> scenarios;  // the scenarios listed (or loaded from a file)
  // Scenarios drawn from distributions (SPEC §12); shared, immutable once loaded.
  std::shared_ptr<const EnsembleConfig> ensemble;
  sim::ControllerConfig controller;
  std::vector<CompareEntry> compare;
  // With goals: the first soft goal's measure whose metric can be the objective.
  ObjectiveConfig objective;
  std::vector<GoalConfig> goals;  // empty: the job is scored by its objective
  std::optional<MetricsConfig> metrics;
  std::optional<TuningConfig> tuning;

  // Range and consistency checks of the whole job (types were checked while parsing).
  std::vector<FieldError> validate() const;
  // Simulated steps of one evaluation of a candidate (Σ over scenarios and ensemble members of
  // samples × substeps).
  std::int64_t steps_per_evaluation() const;
  // What one evaluation costs, in fault-free steps: a step of a scenario with f faults costs
  // 1 + f·kFaultStepCost of them (every fault is evaluated at every stage time and keeps its own
  // metrics), an ensemble member's f its fault distribution's largest count. The service's step
  // budget is in these.
  double step_cost_per_evaluation() const;
  // Scenarios a candidate is simulated on: the listed ones and the ensemble's members.
  std::size_t scenario_count() const;
  // The acceleration the controller reads in the scenarios with sensors (a listed scenario's
  // `sensors` block, an ensemble's members that draw theirs): what the gains file records for
  // flight software (ftc/runtime/acceleration.hpp). None when no scenario has sensors. A tuned
  // job's scenarios must agree on it (validate()); otherwise this is the first one's.
  std::optional<sim::AccelerationSensor> tuned_acceleration() const;
  // Whether a controller of the job reads sensors: a listed scenario's (not exact) or the
  // ensemble's members', which draw theirs.
  bool reads_sensors() const;
};

// Parses and validates; throws InputError(source, every error). A scenario file named by the job
// ("scenarios": {"file": ...}) is read relative to `base_dir`; without one it is refused.
Job parse_job(const nlohmann::json& j, const std::string& source,
              const std::optional<std::filesystem::path>& base_dir = std::nullopt);
Job parse_job_text(const std::string& text, const std::string& source,
                   const std::optional<std::filesystem::path>& base_dir = std::nullopt);
Job load_job(const std::filesystem::path& file);

// The JSON Schema (draft 2020-12) of job files, generated from the same description the loader
// reads with: what `ftctune schema job` prints and docs/job.schema.json holds.
nlohmann::json job_json_schema();

using json_io::json_number;
using json_io::json_number_or;

// Resolved JSON forms (every default filled in). Keys come out sorted, so dump() of these is
// canonical.
nlohmann::json to_json(const Job& job);
nlohmann::json to_json(const PlantConfig& p);
nlohmann::json to_json(const ObjectiveConfig& o);
nlohmann::json to_json(const GoalConfig& g);
// A scenario's JSON form and back: the runtime's (ftc/runtime/scenario_json.hpp).
using runtime::scenario_from_json;

}  // namespace ftc::tune
