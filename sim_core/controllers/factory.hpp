#pragma once
// The controllers by type for one plant shape. Private to sim_core: factory.cpp instantiates
// make_controller for each plant shape.
#include <memory>

#include "controllers/adaptive_neural_pi_fosmc.hpp"
#include "controllers/fosmc.hpp"
#include "controllers/nftsmc.hpp"
#include "controllers/pi_fosmc.hpp"
#include "ftc/sim/controller.hpp"

namespace ftc::sim {

template <int N, int M>
std::unique_ptr<Controller<N, M>> make_controller(const ControllerConfig& config,
                                                  const Plant<N, M>& plant, double sample_time) {
  switch (config.type) {
    case ControllerType::nftsmc:
      return std::make_unique<Nftsmc<N, M>>(config, plant, sample_time);
    case ControllerType::fosmc:
      return std::make_unique<Fosmc<N, M>>(config, plant, sample_time);
    case ControllerType::pi_fosmc:
      return std::make_unique<PiFosmc<N, M>>(config, plant, sample_time);
    case ControllerType::adaptive_neural_pi_fosmc:
      return std::make_unique<AdaptiveNeuralPiFosmc<N, M>>(config, plant, sample_time);
  }
  throw InputError("controller", "type", "unknown controller type");
}

}  // namespace ftc::sim
