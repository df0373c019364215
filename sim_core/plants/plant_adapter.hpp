#pragma once
// AnyPlant for a concrete plant class P: its simulations run in P's batch kernels
// (plants/lane_host.hpp, lanes/closed_loop.hpp), a single one in one lane of the scalar kernel.
// P gives f_constants() (the per-lane constants its lane code, PlantLanes<P>, reads) and its
// kernels (its lanes file, compiled per instruction set). Private to sim_core; each plant's .cpp
// builds its PlantKind with it.
#include <Eigen/LU>
#include <functional>
#include <optional>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "checks.hpp"
#include "ftc/sim/isa.hpp"
#include "ftc/sim/plants.hpp"
#include "plants/lane_host.hpp"

namespace ftc::sim::detail {

template <class P>
class PlantAdapter final : public AnyPlant {
 public:
  using Build = std::function<P(const std::vector<double>&)>;

  // `build` makes a P from parameter values (validated); the model is built from `values`.
  PlantAdapter(std::vector<double> values, Build build)
      : values_(std::move(values)), build_(std::move(build)), plant_(build_(values_)) {}

  const PlantKind& kind() const override { return *find_plant_kind(plant_.model()); }
  int actuators() const override { return actuator_count(); }
  const P& plant() const { return plant_; }

  // One lane of the plant's batch kernel: the code the SIMD lanes run, so that a simulation
  // reproduces any lane of a tuning run to the last bit.
  SimulationResult simulate(const ControllerConfig& controller, const Scenario& scenario,
                            const SimulationOptions& options) const override {
    SimulationResult r;
    LaneTask lane = lane_task(controller, scenario, options);
    lane.result = &r;
    run(std::span<LaneTask>(&lane, 1), Isa::scalar);
    return r;
  }

  void simulate_pack(std::span<const PackTask> tasks, std::span<SimulationResult> results,
                     std::span<std::string> errors) const override {
    simulate_pack(tasks, results, errors, active_isa());
  }
  void simulate_pack(std::span<const PackTask> tasks, std::span<SimulationResult> results,
                     std::span<std::string> errors, Isa isa) const override {
    std::vector<LaneTask> lanes;
    lanes.reserve(tasks.size());
    for (std::size_t i = 0; i < tasks.size(); ++i) {
      errors[i].clear();
      try {
        lanes.push_back(lane_task(*tasks[i].controller, *tasks[i].scenario, *tasks[i].options));
        lanes.back().result = &results[i];
      } catch (const InputError& e) {
        errors[i] = e.what();
      }
    }
    run(lanes, isa);
  }
  int pack_width() const override { return lane_width(active_isa()); }

  std::vector<std::pair<double, double>> command_limits(const Scenario& scenario) const override {
    // The range the loop is given (a trimmed plant's deviation; ±inf without one), within the
    // saturation, as the lane host forms it.
    LaneTask lane;
    trim(plant_, lane);
    std::vector<std::pair<double, double>> out;
    for (int j = 0; j < actuator_count(); ++j) {
      const CommandLimits c =
          detail::command_limits(scenario.saturation.limit(j), lane.lo[j], lane.hi[j]);
      out.emplace_back(c.lo, c.hi);
    }
    return out;
  }

  bool recoverable(const Scenario& scenario) const override {
    constexpr int N = P::kAxes, M = P::kActuators;
    const int m = actuator_count();
    if (scenario.saturation.per_actuator() &&
        scenario.saturation.values.size() != static_cast<std::size_t>(m))
      return false;  // reported by validation
    std::array<bool, M> stuck{};
    std::array<double, M> stuck_at{}, lost{};
    for (const Fault& f : scenario.faults) {
      if (f.actuator < 1 || f.actuator > m) continue;  // reported by validation
      if (f.type == FaultType::stuck) {
        stuck[f.actuator - 1] = true;
        stuck_at[f.actuator - 1] = f.value;
      }
      if (f.type == FaultType::loss_of_effectiveness) lost[f.actuator - 1] += f.fraction;
    }
    typename P::State x0 = P::State::Zero();
    if (scenario.initial_state.size() == static_cast<std::size_t>(2 * N))
      x0 = Eigen::Map<const typename P::State>(scenario.initial_state.data());
    // The simulated plant's actuators, not the model's (a wheel at effectiveness 0 acts on
    // nothing; a true inertia changes no rank).
    std::optional<P> simulated;
    if (!scenario.true_values.empty()) try {
        simulated.emplace(truth(scenario));
      } catch (const InputError&) {
        return false;  // reported by validation
      }
    const P& plant = simulated ? *simulated : plant_;
    const Mat<N, M> G = plant.G(x0);
    // (A plant of one axis makes it a row vector, which Eigen stores row-major.)
    Eigen::Matrix<double, N, Eigen::Dynamic, N == 1 ? Eigen::RowMajor : Eigen::ColMajor, N, M>
        acting(N, 0);
    for (int j = 0; j < m; ++j)
      if (!stuck[j] && lost[j] < 1.0) {
        acting.conservativeResize(Eigen::NoChange, acting.cols() + 1);
        acting.col(acting.cols() - 1) = G.col(j);
      }
    if (acting.cols() < N) return false;
    Eigen::FullPivLU<Eigen::MatrixXd> lu(acting);
    lu.setThreshold(1e-9);
    if (lu.rank() != N) return false;
    // A plant with an operating point (a rotor's hover thrust) must also be able to hold it
    // with what is left, within the limits the loop holds it to: its own range within the
    // scenario's saturation (Hexarotor::trim_feasible).
    if constexpr (requires { plant_.trim_feasible(stuck, stuck_at, lost); }) {
      auto range = plant.thrust_range();
      const auto t = plant.actuator_trim();
      for (int j = 0; j < m; ++j) {
        const double u_max = scenario.saturation.limit(j);
        range.floor[j] = std::max(range.floor[j], t.u0[j] - u_max);
        range.cap[j] = std::min(range.cap[j], t.u0[j] + u_max);
      }
      return plant.trim_feasible(stuck, stuck_at, lost, range);
    }
    return true;
  }

 private:
  // The simulated plant of a scenario that gives true values of uncertain parameters (model
  // mismatch).
  P truth(const Scenario& scenario) const {
    const std::vector<double> v = kind().with_true_values(values_, scenario.true_values, "");
    throw_if_errors("scenario " + scenario.name, kind().validate(v, ""));
    return build_(v);
  }

  // A validated simulation for the batch kernels; throws InputError like simulate().
  LaneTask lane_task(const ControllerConfig& controller, const Scenario& scenario,
                     const SimulationOptions& options) const {
    LaneTask lane;
    lane.config = checked_config(controller, scenario.sample_time);
    throw_if_errors("scenario " + scenario.name, scenario.validate("", P::kAxes, actuator_count()));
    lane.scenario = &scenario;
    plant_extent(plant_, lane);
    lane.options = &options;
    const auto model = plant_.f_constants();
    static_assert(model.size() <= kMaxPlantConstants);
    std::copy(model.begin(), model.end(), lane.model.begin());
    lane.truth = lane.model;
    if (!scenario.true_values.empty()) {
      const P simulated = truth(scenario);
      const auto truth_constants = simulated.f_constants();
      std::copy(truth_constants.begin(), truth_constants.end(), lane.truth.begin());
      trim(simulated, lane);
    } else {
      trim(plant_, lane);
    }
    return lane;
  }

  // The plant's own m: fewer than P's M for a rigid body with fewer actuators.
  int actuator_count() const {
    if constexpr (requires { plant_.actuator_count(); })
      return plant_.actuator_count();
    else
      return P::kActuators;
  }

  // A plant whose actuators work about an operating point gives actuator_trim(): u0 and the
  // limits of the deviation per actuator (PackSetup::u0, lo, hi).
  static constexpr bool kTrimmed = requires(const P& p) { p.actuator_trim(); };
  static void trim(const P& p, LaneTask& lane) {
    if constexpr (kTrimmed) {
      static_assert(P::kActuators <= kMaxActuators);
      const auto t = p.actuator_trim();
      for (int j = 0; j < P::kActuators; ++j) {
        lane.u0[j] = t.u0[j];
        lane.lo[j] = t.lo[j];
        lane.hi[j] = t.hi[j];
      }
    }
  }

  void run(std::span<LaneTask> lanes, Isa isa) const {
    if (constant_G_)
      run_lanes<P>(lanes, &G_, &G_pinv_, kTrimmed, isa);
    else
      run_lanes<P>(lanes, nullptr, nullptr, kTrimmed, isa);
  }

  std::vector<double> values_;
  Build build_;
  P plant_;
  // G and G⁺ when constant (read once, as the scalar controllers do).
  bool constant_G_ = plant_.input_matrix_is_constant();
  Mat<P::kAxes, P::kActuators> G_ = plant_.G(P::State::Zero());
  Mat<P::kActuators, P::kAxes> G_pinv_ = plant_.G_pinv(P::State::Zero());
};

}  // namespace ftc::sim::detail
