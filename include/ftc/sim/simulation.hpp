#pragma once
// The sampled-data closed loop of SPEC §4.
//
//   X = X(0); u_prev = 0
//   for k = 0 .. N-1, t = k Ts:
//     a_k = f(X) + G·applied(t, u_prev) + Δ(t)     acceleration sensor, before the new command
//     u_k = controller.step(t, X1, X2, a_k)
//     metrics.sample(t, X, u_k)
//     substeps × RK4 with u_d = u_k held (zero-order hold); faults and Δ at each stage time
//     stop, marked diverged, when any |X_i| is NaN, inf or > 1e6
//
// A diverging run is a result (metrics.diverged), never an exception.
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <vector>

#include "ftc/sim/controller.hpp"
#include "ftc/sim/metrics.hpp"
#include "ftc/sim/plant.hpp"
#include "ftc/sim/scenario.hpp"

namespace ftc::sim {

inline constexpr double kDivergenceBound = 1e6;

struct SimulationOptions {
  Window window;                      // objective window; default the whole run
  std::vector<Window> extra_windows;  // further windows for ise/iae/itae
  std::int64_t record_every = 0;      // record every k-th sample; 0 = no trajectory
  MetricSettings metrics;             // settling threshold and steady-state tail
};

// Recorded samples, one row each: t, X (2n values), the commanded u_d (m) and the applied u
// after faults and saturation (m), stored flat so that any plant shape fits one type.
struct Trajectory {
  int axes = 0;
  int actuators = 0;
  std::vector<double> values;

  std::size_t width() const { return 1 + 2 * static_cast<std::size_t>(axes + actuators); }
  std::size_t rows() const { return width() == 1 ? 0 : values.size() / width(); }
  std::span<const double> row(std::size_t i) const {
    return std::span<const double>(values).subspan(i * width(), width());
  }
  double t(std::size_t i) const { return values[i * width()]; }
  std::span<const double> x(std::size_t i) const { return row(i).subspan(1, 2 * axes); }
  std::span<const double> u_d(std::size_t i) const {
    return row(i).subspan(1 + 2 * axes, actuators);
  }
  std::span<const double> u(std::size_t i) const {
    return row(i).subspan(1 + 2 * axes + actuators, actuators);
  }
};

struct SimulationResult {
  Metrics metrics;
  std::int64_t samples = 0;         // samples simulated (fewer than N when diverged)
  std::vector<double> final_state;  // X at t = samples · Ts
  Trajectory trajectory;
  // For a plant whose model holds only in part of the state space (rigid_body: |θ| < 85°, away
  // from the Euler angles' singularity), whether the run left it at some sample; absent for the
  // others. The metrics still count.
  std::optional<bool> model_invalid;
};

// Runs one scenario. The controller is reset first. Throws InputError only for an invalid
// scenario; the run itself never throws. Defined for the shapes of the registered plants
// (sim_core/plants/registry.cpp); for a registered plant class the loop is compiled for it.
template <int N, int M>
SimulationResult simulate(const Plant<N, M>& plant, Controller<N, M>& controller,
                          const Scenario& scenario, const SimulationOptions& options = {});

}  // namespace ftc::sim
