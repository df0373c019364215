#pragma once
// Simulating one controller configuration on every scenario of a job and scoring it (SPEC §6):
// objective = the job's metric in its window, aggregated over scenarios (mean or max);
// fitness J = 1 / objective, and J = 0 when any scenario diverged.
#include <cstdint>
#include <nlohmann/json_fwd.hpp>
#include <span>
#include <string>
#include <vector>

#include "ftc/sim/controller_config.hpp"
#include "ftc/sim/metrics.hpp"
#include "ftc/sim/plants.hpp"
#include "ftc/sim/simulation.hpp"
#include "ftc/tune/job/job.hpp"

namespace ftc::tune {

// Simulation options for a scenario of a job: the objective window plus the fault segments
// (before the first onset, between onsets, after the last) as extra windows.
sim::SimulationOptions simulation_options(const Job& job, const sim::Scenario& scenario,
                                          std::int64_t record_every = 0);

// One scenario of the job with the given controller. Never throws for a diverging run.
sim::SimulationResult simulate_scenario(const Job& job, const sim::AnyPlant& plant,
                                        const sim::ControllerConfig& controller,
                                        std::size_t scenario, std::int64_t record_every = 0);

double aggregate_objective(const ObjectiveConfig& objective, std::span<const sim::Metrics> runs);
double fitness_of(double objective);  // 1/objective; 0 for inf/NaN; +inf for 0

struct Evaluation {
  std::vector<sim::Metrics> scenarios;
  double objective = 0.0;
  double fitness = 0.0;
  bool diverged = false;
};

// Objective and fitness of a controller from its metrics on every scenario of the job.
Evaluation score(const ObjectiveConfig& objective, std::vector<sim::Metrics> per_scenario);

// CSV of a recorded trajectory: time, x1..x2n, ud1..udm (commanded), u1..um (applied).
std::string trajectory_csv(const sim::Trajectory& trajectory);

// Metrics of one scenario as written to metrics.json; ise/iae/itae in the objective window,
// infinite values as null.
nlohmann::json metrics_json(const sim::Metrics& m);

}  // namespace ftc::tune
