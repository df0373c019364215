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
  return visit_controller_type(config.type, [&](auto t) -> std::unique_ptr<Controller<N, M>> {
    using C = typename detail::ControllerClass<decltype(t)::value>::template type<N, M>;
    static_assert(C::kModelBased == controller_info(decltype(t)::value).model_based);
    return std::make_unique<C>(config, plant, sample_time);
  });
}

}  // namespace ftc::sim
