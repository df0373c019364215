#pragma once
// The JSON form of a controller, shared by job files, gains files and --set overrides:
// {"type": "pi_fosmc", "c1": 10, ...}; every field optional with its Table 1 default, fields of
// other controller types rejected. Built from the controller field table (ControllerField), so
// names, ranges, units and the JSON Schema come from one place.
#include <memory>
#include <nlohmann/json_fwd.hpp>
#include <string>
#include <vector>

#include "ftc/runtime/schema.hpp"
#include "ftc/sim/controller_config.hpp"
#include "ftc/sim/input_error.hpp"

namespace ftc::runtime {

// The controller object, one case per controller type.
std::shared_ptr<const schema::Shape<sim::ControllerConfig>> controller_shape();

// Parses a controller object at JSON path `path`; problems are appended to `errors` (ranges are
// checked by ControllerConfig::validate, not here).
sim::ControllerConfig parse_controller(const nlohmann::json& j, const std::string& path,
                                       std::vector<FieldError>& errors);

// Every parameter of the controller's type, α1 resolved; integer fields as integers.
nlohmann::json to_json(const sim::ControllerConfig& c);

}  // namespace ftc::runtime
