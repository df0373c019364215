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

#include "ftc/sim/controller_config.hpp"
#include "ftc/sim/input_error.hpp"
#include "ftc/sim/metrics.hpp"
#include "ftc/sim/plants.hpp"
#include "ftc/sim/scenario.hpp"
#include "ftc/runtime/controller_json.hpp"

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

enum class AlgorithmType { bat, random };
const char* to_string(AlgorithmType a);

struct AlgorithmConfig {
  AlgorithmType type = AlgorithmType::bat;
  int population = 10;  // M
  int iterations = 10;  // T
  double f_min = 0.0;
  double f_max = 2.0;
  double loudness = 0.95;   // A0
  double pulse_rate = 0.9;  // r0
  double loudness_decay = 0.9;
  double pulse_rate_growth = 0.9;

  std::vector<FieldError> validate(const std::string& path) const;
  // M·(T+1): the number of objective evaluations of a run.
  std::int64_t evaluations() const {
    return static_cast<std::int64_t>(population) * (iterations + 1);
  }
};

struct ParameterBounds {
  std::string name;  // a tunable field of the controller
  double lower = 0.0;
  double upper = 0.0;
};

struct TuningConfig {
  std::vector<ParameterBounds> parameters;
  AlgorithmConfig algorithm;
  std::uint64_t seed = 1;
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

// Numbers in output JSON: non-finite values (a diverged run's +inf) are written as null, and
// read back as `if_null`.
nlohmann::json json_number(double v);
double json_number_or(const nlohmann::json& j, double if_null);

// Resolved JSON forms (every default filled in). Keys come out sorted, so dump() of these is
// canonical.
nlohmann::json to_json(const Job& job);
nlohmann::json to_json(const PlantConfig& p);
nlohmann::json to_json(const ObjectiveConfig& o);
nlohmann::json to_json(const sim::Scenario& s);

}  // namespace ftc::tune
