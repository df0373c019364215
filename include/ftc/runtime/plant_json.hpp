#pragma once
// The JSON form of a plant, shared by job and gains files: {"model": "spacecraft",
// "inertia": [...], ...}, one case per registered plant kind, built from the kind's parameter
// table (names, defaults, ranges, units), so a new plant needs no change here.
#include <memory>

#include "ftc/runtime/schema.hpp"
#include "ftc/sim/plants.hpp"

namespace ftc::runtime {

std::shared_ptr<const schema::Shape<sim::PlantSpec>> plant_shape();

}  // namespace ftc::runtime
