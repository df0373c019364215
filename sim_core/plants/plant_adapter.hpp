#pragma once
// AnyPlant for a concrete plant class P: the loop compiled for P, so that its f and G inline.
// Private to sim_core; each plant's .cpp builds its PlantKind with it.
//
// The controller is called through its interface, one virtual call a sample. Compiling the loop
// for each controller class as well was measured slower (10 % on the landscape): GCC's inliner
// then spends its budget on the controller and leaves the plant's f out of line. For the same
// reason this header must not see the controller classes (their make_controller lives in
// controllers/factory.cpp): with them in sight GCC devirtualises the call speculatively and
// bloats the loop (16 % slower).
#include <utility>

#include "ftc/sim/plants.hpp"
#include "simulation_loop.hpp"

namespace ftc::sim::detail {

template <class P>
class PlantAdapter final : public AnyPlant {
 public:
  explicit PlantAdapter(P plant) : plant_(std::move(plant)) {}

  const PlantKind& kind() const override { return *find_plant_kind(plant_.model()); }
  const P& plant() const { return plant_; }

  SimulationResult simulate(const ControllerConfig& controller, const Scenario& scenario,
                            const SimulationOptions& options) const override {
    const auto c = make_controller(controller, plant_, scenario.sample_time);
    throw_if_errors("scenario " + scenario.name, scenario.validate("", P::kAxes, P::kActuators));
    return run(plant_, *c, scenario, options);
  }

 private:
  P plant_;
};

}  // namespace ftc::sim::detail
