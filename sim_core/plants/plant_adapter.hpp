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
#include <Eigen/LU>
#include <functional>
#include <span>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "checks.hpp"
#include "ftc/sim/isa.hpp"
#include "ftc/sim/plants.hpp"
#include "ftc/sim/spacecraft.hpp"
#include "plants/spacecraft_pack.hpp"
#include "simulation_loop.hpp"

namespace ftc::sim::detail {

template <class P>
class PlantAdapter final : public AnyPlant {
 public:
  using Build = std::function<P(const std::vector<double>&)>;

  // `build` makes a P from parameter values (validated); the model is built from `values`.
  PlantAdapter(std::vector<double> values, Build build)
      : values_(std::move(values)), build_(std::move(build)), plant_(build_(values_)) {}

  const PlantKind& kind() const override { return *find_plant_kind(plant_.model()); }
  const P& plant() const { return plant_; }

  SimulationResult simulate(const ControllerConfig& controller, const Scenario& scenario,
                            const SimulationOptions& options) const override {
    if constexpr (std::is_same_v<P, Spacecraft>) {
      // The batch kernel with one lane: the code the SIMD lanes run, so that a simulation
      // reproduces any lane of a tuning run to the last bit.
      SimulationResult r;
      SpacecraftLane lane = spacecraft_lane(controller, scenario, options);
      lane.result = &r;
      run_spacecraft_lanes(std::span<SpacecraftLane>(&lane, 1), plant_.G(P::State::Zero()),
                           plant_.G_pinv(P::State::Zero()), Isa::scalar);
      return r;
    } else {
      const auto c = make_controller(controller, plant_, scenario.sample_time);
      throw_if_errors("scenario " + scenario.name, scenario.validate("", P::kAxes, P::kActuators));
      if (scenario.inertia.empty()) return run(plant_, *c, scenario, options);
      // Model mismatch: the controller keeps the model, the loop simulates the true plant.
      return run(truth(scenario), *c, scenario, options);
    }
  }

  void simulate_pack(std::span<const PackTask> tasks, std::span<SimulationResult> results,
                     std::span<std::string> errors) const override {
    if constexpr (std::is_same_v<P, Spacecraft>) {
      std::vector<SpacecraftLane> lanes;
      lanes.reserve(tasks.size());
      for (std::size_t i = 0; i < tasks.size(); ++i) {
        errors[i].clear();
        try {
          lanes.push_back(
              spacecraft_lane(*tasks[i].controller, *tasks[i].scenario, *tasks[i].options));
          lanes.back().result = &results[i];
        } catch (const InputError& e) {
          errors[i] = e.what();
        }
      }
      run_spacecraft_lanes(lanes, plant_.G(P::State::Zero()), plant_.G_pinv(P::State::Zero()),
                           active_isa());
    } else {
      AnyPlant::simulate_pack(tasks, results, errors);
    }
  }
  int pack_width() const override {
    if constexpr (std::is_same_v<P, Spacecraft>)
      return lane_width(active_isa());
    else
      return 1;
  }

  bool recoverable(const Scenario& scenario) const override {
    constexpr int N = P::kAxes, M = P::kActuators;
    std::array<bool, M> stuck{};
    std::array<double, M> lost{};
    for (const Fault& f : scenario.faults) {
      if (f.actuator < 1 || f.actuator > M) continue;  // reported by validation
      if (f.type == FaultType::stuck) stuck[f.actuator - 1] = true;
      if (f.type == FaultType::loss_of_effectiveness) lost[f.actuator - 1] += f.fraction;
    }
    typename P::State x0 = P::State::Zero();
    if (scenario.initial_state.size() == static_cast<std::size_t>(2 * N))
      x0 = Eigen::Map<const typename P::State>(scenario.initial_state.data());
    const Mat<N, M> G = plant_.G(x0);
    Eigen::Matrix<double, N, Eigen::Dynamic, 0, N, M> acting(N, 0);
    for (int j = 0; j < M; ++j)
      if (!stuck[j] && lost[j] < 1.0) {
        acting.conservativeResize(Eigen::NoChange, acting.cols() + 1);
        acting.col(acting.cols() - 1) = G.col(j);
      }
    if (acting.cols() < N) return false;
    Eigen::FullPivLU<Eigen::MatrixXd> lu(acting);
    lu.setThreshold(1e-9);
    return lu.rank() == N;
  }

 private:
  // The simulated plant of a scenario that names a true inertia (model mismatch).
  P truth(const Scenario& scenario) const {
    const std::vector<double> v = kind().with_inertia(values_, scenario.inertia, "/inertia");
    throw_if_errors("scenario " + scenario.name, kind().validate(v, ""));
    return build_(v);
  }

  // A validated spacecraft simulation for the batch kernels; throws InputError like simulate().
  SpacecraftLane spacecraft_lane(
      const ControllerConfig& controller, const Scenario& scenario,
      const SimulationOptions& options) const requires std::is_same_v<P, Spacecraft> {
    SpacecraftLane lane;
    lane.config = checked_config(controller, scenario.sample_time);
    throw_if_errors("scenario " + scenario.name, scenario.validate("", P::kAxes, P::kActuators));
    lane.scenario = &scenario;
    lane.options = &options;
    lane.model = plant_.f_constants();
    lane.truth = scenario.inertia.empty() ? lane.model : truth(scenario).f_constants();
    return lane;
  }

  std::vector<double> values_;
  Build build_;
  P plant_;
};

}  // namespace ftc::sim::detail
