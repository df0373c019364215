#pragma once
// The spacecraft's simulations through the batch kernels (lanes/pack.hpp): grouping into packs,
// and the host side of a pack (exogenous inputs, metrics, trajectories). Private to sim_core.
#include <array>
#include <span>

#include "ftc/sim/controller_config.hpp"
#include "ftc/sim/isa.hpp"
#include "ftc/sim/scenario.hpp"
#include "ftc/sim/simulation.hpp"
#include "ftc/sim/types.hpp"

namespace ftc::sim::detail {

// One validated simulation: its controller (checked, α1 resolved), scenario and options, the
// constants kx, ky, kz, ω0 of the simulated plant and of the controller's model.
struct SpacecraftLane {
  ControllerConfig config;
  const Scenario* scenario = nullptr;
  const SimulationOptions* options = nullptr;
  std::array<double, 4> truth{}, model{};
  SimulationResult* result = nullptr;
};

// Runs the lanes in packs of the instruction set's width (lanes that cannot share a pack run in
// different ones), writing each result.
void run_spacecraft_lanes(std::span<SpacecraftLane> lanes, const Mat34& G, const Mat43& G_pinv,
                          Isa isa);

}  // namespace ftc::sim::detail
