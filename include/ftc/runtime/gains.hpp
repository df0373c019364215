#pragma once
// Loading a gains file (`ftctune.gains/1`) at run time: what a flight-software integrator calls
// to get a ready controller with the tuned gains.
//
//   const ftc::sim::Spacecraft plant(params);                 // the model-based laws need f, G⁺
//   auto controller = ftc::runtime::load_controller("gains.json", plant, 0.001);
//   controller->reset();
//   every Ts:  u_d = controller->step(t, X1, X2, a);
//
// The loader refuses a file with another schema, a missing or unknown field, a controller
// field out of its valid range, tuned values that disagree with the controller, or gains tuned
// for another sample time than the caller's — each with an InputError naming the JSON path.
#include <filesystem>
#include <memory>
#include <nlohmann/json_fwd.hpp>
#include <string>
#include <utility>
#include <vector>

#include "ftc/sim/controller.hpp"
#include "ftc/sim/controller_config.hpp"
#include "ftc/sim/plant.hpp"

namespace ftc::runtime {

inline constexpr const char* kGainsSchema = "ftctune.gains/1";

struct Gains {
  sim::ControllerConfig controller;                   // every parameter, tuned ones included
  std::vector<std::pair<std::string, double>> tuned;  // name → value
  double sample_time = 0.0;                           // Ts the gains were tuned for, s
  std::string job_name;
  std::string job_sha256;
};

Gains parse_gains(const nlohmann::json& document, const std::string& source);
Gains read_gains(const std::filesystem::path& file);

// Builds the controller; throws InputError when `sample_time` differs from the gains' one.
std::unique_ptr<sim::Controller> make_controller(const Gains& gains, const sim::Plant& plant,
                                                 double sample_time);
std::unique_ptr<sim::Controller> load_controller(const std::filesystem::path& file,
                                                 const sim::Plant& plant, double sample_time);

}  // namespace ftc::runtime
