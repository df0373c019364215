#pragma once
// The JSON form of a fault scenario (SPEC §3, §4; jobs/README.md's "scenario"), shared by job
// files, scenarios files and the MPI ranks that are sent their scenarios: run length, sampling,
// initial state, disturbance, faults, saturation, the actuators' dynamics and the true values of
// uncertain plant parameters. Like the plant's and the controller's shapes, one description
// reads, checks, writes and describes it (the JSON Schema).
#include <memory>
#include <nlohmann/json_fwd.hpp>
#include <string>
#include <vector>

#include "ftc/runtime/schema.hpp"
#include "ftc/sim/plants.hpp"
#include "ftc/sim/scenario.hpp"

namespace ftc::runtime {

std::shared_ptr<const schema::Shape<sim::Scenario>> scenario_shape();
// A sensors block's `acceleration` ({"source": "ideal"} or {"source": "differentiated",
// "time_constant": τ}), also the acceleration path a gains file records.
std::shared_ptr<const schema::Shape<sim::AccelerationSensor>> acceleration_shape();

// A scenario's resolved JSON form (every default filled in, keys sorted).
nlohmann::json to_json(const sim::Scenario& s);
// A scenario from its JSON form (strict, as in a job; not checked against a plant): throws
// InputError(source, every error).
sim::Scenario scenario_from_json(const nlohmann::json& j, const std::string& source);

// The uncertain parameters of the registered plants (sim::PlantKind::uncertain), each once in
// registry order: the scenario keys of model mismatch's true values and, with "_scale", the
// ensemble's keys. A job may use only its own plant's (checked against the plant).
struct UncertainKey {
  std::string parameter;
  std::string models;                     // the plants that declare it: "spacecraft, hexarotor"
  std::string meaning;                    // the first declaring plant's words
  const sim::PlantParameter* declared{};  // the first declaring plant's parameter (unit, range)
  bool per_actuator = false;              // one value per actuator (UncertainParameter's)
  bool tensor = false;                    // a 3×3 tensor or its 3 principal moments
};
std::vector<UncertainKey> uncertain_keys();

// A name that can name a file: 1-100 letters, digits, `_ - .`, not starting with `.`.
inline constexpr const char* kNamePattern = "^[A-Za-z0-9_-][A-Za-z0-9_.-]{0,99}$";

}  // namespace ftc::runtime
