#pragma once
// Loading a gains file (`ftctune.gains/1`) at run time: what a flight-software integrator calls
// to get a ready controller with the tuned gains.
//
//   const ftc::sim::Spacecraft plant(params);                 // the model-based laws need f, G⁺
//   auto controller = ftc::runtime::load_controller("gains.json", plant, 0.001);  // Controller<3,
//   4> controller->reset(); every Ts:  u_d = controller->step(t, X1, X2, a);
//
// The loader refuses a file with another schema, a missing or unknown field, a controller
// field out of its valid range, tuned values that disagree with the controller, or gains tuned
// for another sample time than the caller's — each with an InputError naming the JSON path.
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

namespace ftc::runtime {

inline constexpr const char* kGainsSchema = "ftctune.gains/1";

struct Gains {
  sim::ControllerConfig controller;                   // every parameter, tuned ones included
  std::vector<std::pair<std::string, double>> tuned;  // name → value
  double sample_time = 0.0;                           // Ts the gains were tuned for, s
  sim::PlantSpec plant;                               // the plant they were tuned on
  std::optional<double> fitness;                      // null in the file: every candidate diverged
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

// Builds the controller for a plant of any shape; throws InputError when `sample_time` differs
// from the gains' one.
template <int N, int M>
std::unique_ptr<sim::Controller<N, M>> make_controller(const Gains& gains,
                                                       const sim::Plant<N, M>& plant,
                                                       double sample_time) {
  check_sample_time(gains, sample_time);
  return sim::make_controller(gains.controller, plant, sample_time);
}
template <int N, int M>
std::unique_ptr<sim::Controller<N, M>> load_controller(const std::filesystem::path& file,
                                                       const sim::Plant<N, M>& plant,
                                                       double sample_time) {
  return make_controller(read_gains(file), plant, sample_time);
}

}  // namespace ftc::runtime
