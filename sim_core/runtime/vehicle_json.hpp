#pragma once
// The job-file shapes of the rigid_body and multirotor plants (SPEC §17), whose parameters are
// structured (a tensor, an actuators block, a rotor list) rather than one number or array each.
// Private to ftc::runtime: plant_json.cpp and scenario_json.cpp use them.
#include <memory>
#include <vector>

#include "ftc/runtime/schema.hpp"
#include "ftc/sim/plants.hpp"

namespace ftc::runtime::detail {

// The shape of a kind whose job form is structured (rigid_body, multirotor); null for the
// others, whose parameters are each a number or an array (plant_json.cpp's plant_field).
std::shared_ptr<schema::Object<sim::PlantSpec>> structured_plant_object(const sim::PlantKind& kind);

// A scenario's true inertia given as a 3×3 tensor: its 9 values, row-major, into `out` (errors
// at `path`); false when `v` is not a nested array (then it is read as a flat one).
bool read_tensor_values(const schema::json& v, const std::string& path, std::vector<double>& out,
                        schema::Errors& e);

}  // namespace ftc::runtime::detail
