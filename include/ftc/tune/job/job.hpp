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
#include "ftc/sim/controller_config.hpp"
#include "ftc/sim/input_error.hpp"
#include "ftc/sim/metrics.hpp"
#include "ftc/sim/plants.hpp"
#include "ftc/sim/scenario.hpp"
#include "ftc/tune/optimizers/optimizer.hpp"

namespace ftc::tune {

inline constexpr const char* kJobSchema = "ftctune.job/1";

using runtime::parse_controller;
using runtime::to_json;

// The plant of a job: its model name and parameter values (sim_core's plant registry describes
// them); the loader fills in every default.
using PlantConfig = sim::PlantSpec;

enum class Aggregate { mean, max };
const char* to_string(Aggregate a);

struct ObjectiveConfig {
  sim::Metric metric = sim::Metric::ise;
  sim::Window window;  // default: the whole run
  Aggregate aggregate = Aggregate::mean;
};

struct ParameterBounds {
  std::string name;  // a tunable field of the controller
  double lower = 0.0;
  double upper = 0.0;
};

struct TuningConfig {
  std::vector<ParameterBounds> parameters;
  AlgorithmPtr algorithm = default_algorithm();  // the Bat algorithm with Table 1 settings
  std::uint64_t seed = 1;

  static AlgorithmPtr default_algorithm();
};

struct CompareEntry {
  std::string label;  // shown in comparisons; defaults to the controller type
  sim::ControllerConfig controller;
};

struct Job {
  std::string name;
  PlantConfig plant;
  std::vector<sim::Scenario> scenarios;
  sim::ControllerConfig controller;
  std::vector<CompareEntry> compare;
  ObjectiveConfig objective;
  std::optional<TuningConfig> tuning;

  // Range and consistency checks of the whole job (types were checked while parsing).
  std::vector<FieldError> validate() const;
  // Simulated steps of one evaluation of a candidate (Σ over scenarios of samples × substeps).
  std::int64_t steps_per_evaluation() const;
};

// Parses and validates; throws InputError(source, every error).
Job parse_job(const nlohmann::json& j, const std::string& source);
Job parse_job_text(const std::string& text, const std::string& source);
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
nlohmann::json to_json(const sim::Scenario& s);

}  // namespace ftc::tune
