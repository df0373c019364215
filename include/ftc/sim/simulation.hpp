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
#include <cstdint>
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
};

struct TrajectoryRow {
  double t;
  State x;
  Vec4 u_d;  // commanded
  Vec4 u;    // applied, after faults and saturation
};

struct SimulationResult {
  Metrics metrics;
  std::int64_t samples = 0;           // samples simulated (fewer than N when diverged)
  State final_state = State::Zero();  // X at t = samples · Ts
  std::vector<TrajectoryRow> trajectory;
};

// Runs one scenario. The controller is reset first. Throws InputError only for an invalid
// scenario; the run itself never throws.
SimulationResult simulate(const Plant& plant, Controller& controller, const Scenario& scenario,
                          const SimulationOptions& options = {});

}  // namespace ftc::sim
