#pragma once
// Loading a gains file (`ftctune.gains/1`) at run time: what a flight-software integrator calls
// to get a ready controller with the tuned gains.
//
//   const ftc::sim::Spacecraft plant(params);                 // the model-based laws need f, G⁺
//   auto controller = ftc::runtime::load_controller("gains.json", plant, 0.001);  // Controller<3,
//   4> controller->reset(); every Ts:  u_d = controller->step(t, X1, X2, a);
//
// The loader refuses a file with another schema, a missing or unknown field, a controller
// field out of its valid range, tuned values that disagree with the controller, a fitness of 0
// or null (every candidate diverged in tuning), a run stopped before its last iteration
// (optimizer.completed false), or gains tuned for another sample time or another plant model
// than the caller's — each with an InputError naming the JSON path. The plant's parameters are
// compared when the caller gives them (check_plant), the job when the caller knows its SHA-256
// (check_job). The file has no hash of its own; it is written atomically, so a torn file is a
// JSON error.
#include <filesystem>
#include <memory>
#include <nlohmann/json_fwd.hpp>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "ftc/sim/controller.hpp"
#include "ftc/sim/controller_config.hpp"
#include "ftc/sim/plant.hpp"
#include "ftc/sim/plants.hpp"
#include "ftc/sim/sensors.hpp"

namespace ftc::runtime {

inline constexpr const char* kGainsSchema = "ftctune.gains/1";

struct Gains {
  sim::ControllerConfig controller;                   // every parameter, tuned ones included
  std::vector<std::pair<std::string, double>> tuned;  // name → value
  double sample_time = 0.0;                           // Ts the gains were tuned for, s
  sim::PlantSpec plant;                               // the plant they were tuned on
  // The acceleration the controller read in tuning, when the job's scenarios have sensors
  // (ftc/sim/sensors.hpp): `differentiated` means flight software must feed step() the gyro
  // rates differentiated through the same low-pass (AccelerationEstimator,
  // ftc/runtime/acceleration.hpp). Absent: tuned on the exact acceleration (an ideal sensor).
  std::optional<sim::AccelerationSensor> acceleration;
  std::optional<double> fitness;  // > 0: the loader refuses a null or 0 (all candidates diverged)
  std::string job_name;
  std::string job_sha256;
};

Gains parse_gains(const nlohmann::json& document, const std::string& source);
Gains read_gains(const std::filesystem::path& file);

// The JSON Schema (draft 2020-12) of gains files, generated from the description the loader
// reads with: what `ftctune schema gains` prints and docs/gains.schema.json holds.
nlohmann::json gains_json_schema();

// Throws InputError when `sample_time` is not the one the gains were tuned for (equal within
// 1e-12 relative: a Ts written in a file and re-read may differ in its last bit).
void check_sample_time(const Gains& gains, double sample_time);

// Throws InputError when the gains were tuned on another job than the one whose canonical
// SHA-256 is given (`ftctune validate` prints it; the tuner's canonical_job_sha256()).
void check_job(const Gains& gains, const std::string& job_sha256);
// Throws InputError when the gains were tuned on another plant model (Plant::model()).
void check_plant_model(const Gains& gains, const std::string& model);
// Throws InputError, naming each parameter that differs (equal within 1e-12 relative), when
// the gains were tuned on another plant than `expected` (empty values: the model's defaults).
void check_plant(const Gains& gains, const sim::PlantSpec& expected);

// Builds the controller for a plant of any shape; throws InputError when `sample_time` differs
// from the gains' one or `plant` is of another model than the one they were tuned on.
template <int N, int M>
std::unique_ptr<sim::Controller<N, M>> make_controller(const Gains& gains,
                                                       const sim::Plant<N, M>& plant,
                                                       double sample_time) {
  check_sample_time(gains, sample_time);
  check_plant_model(gains, plant.model());
  return sim::make_controller(gains.controller, plant, sample_time);
}
template <int N, int M>
std::unique_ptr<sim::Controller<N, M>> load_controller(const std::filesystem::path& file,
                                                       const sim::Plant<N, M>& plant,
                                                       double sample_time) {
  return make_controller(read_gains(file), plant, sample_time);
}

}  // namespace ftc::runtime
