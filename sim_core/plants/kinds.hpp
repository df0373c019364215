#pragma once
// The description of each shipped plant, defined in the plant's own .cpp. Private to sim_core.
#include "ftc/sim/plants.hpp"

namespace ftc::sim::detail {

PlantKind spacecraft_kind();
PlantKind manipulator_kind();
PlantKind hexarotor_kind();
PlantKind rigid_body_kind();
PlantKind multirotor_kind();

}  // namespace ftc::sim::detail
