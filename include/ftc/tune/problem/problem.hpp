#pragma once
// A job as a tuning problem (SPEC §6): the decision vector names values of the controller fields
// listed under tuning.parameters; a candidate is simulated on every scenario of the job and
// scored by the job's objective, the metric in the window aggregated over the scenarios;
// fitness J = 1/objective, and J = 0 when a scenario diverged. The problem owns all of that:
// evaluators only run the simulations it describes as tasks, optimisers only see fitness.
//
// Copyable (copies share the immutable plant) and immutable after construction, so any number
// of threads may simulate and score at once.
//
// For use inside another optimiser, objective(x) is the one call: the objective of the
// controller with the tuned fields set from x, simulated on the calling thread.
#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "ftc/sim/controller_config.hpp"
#include "ftc/sim/metrics.hpp"
#include "ftc/sim/plants.hpp"
#include "ftc/sim/simulation.hpp"
#include "ftc/tune/evaluators/batch_evaluator.hpp"
#include "ftc/tune/job/job.hpp"
#include "ftc/tune/optimizers/optimizer.hpp"
#include "ftc/tune/optimizers/search_space.hpp"

namespace ftc::tune {

// A candidate's score.
struct Evaluation {
  std::vector<sim::Metrics> scenarios;  // per scenario of the job
  double objective = 0.0;               // the aggregate; +inf when a scenario diverged
  double fitness = 0.0;                 // 1/objective; 0 when diverged
  bool diverged = false;
};

// A candidate's score with what else its simulations gave.
struct CandidateOutcome {
  Evaluation evaluation;
  std::string error;  // non-empty when a simulation could not run (fitness is then 0)
  std::vector<sim::Trajectory> trajectories;  // per scenario, when recorded
};

// The aggregate of the job's metric over its scenarios (mean or max).
double aggregate_objective(const ObjectiveConfig& objective, std::span<const sim::Metrics> runs);
double fitness_of(double objective);  // 1/objective; 0 for inf/NaN; +inf for 0

struct ObjectiveOptions {
  // What a diverged candidate's objective is: +inf when unset; an optimiser that cannot handle
  // infinities can ask for a large finite penalty (e.g. 1e30) instead.
  std::optional<double> diverged_penalty;
};

class TuningProblem {
 public:
  // Throws InputError when the job does not validate. A job without a tuning section is a
  // problem of dimension 0 (its own controller only: simulate, compare).
  explicit TuningProblem(Job job);

  const Job& job() const { return *job_; }
  const sim::AnyPlant& plant() const { return *plant_; }
  const SearchSpace& space() const { return space_; }
  std::size_t scenarios() const { return job_->scenarios.size(); }

  // The job's controller with the tuned fields set from x (in space().names order).
  sim::ControllerConfig controller_for(std::span<const double> x) const;
  // The simulation options of a scenario: the objective window and the fault segments (before
  // the first onset, between onsets, after the last) as extra windows.
  sim::SimulationOptions simulation_options(std::size_t scenario,
                                            std::int64_t record_every = 0) const;
  // One scenario with one controller. Throws InputError for an invalid controller; a diverging
  // run is a result.
  sim::SimulationResult simulate(const sim::ControllerConfig& controller, std::size_t scenario,
                                 std::int64_t record_every = 0) const;

  // The tasks of n candidates: every (candidate, scenario) pair, candidate-major.
  std::vector<SimulationTask> tasks(std::size_t candidates) const;
  // A candidate's score from its metrics on every scenario.
  Evaluation score(std::vector<sim::Metrics> per_scenario) const;
  // Simulates and scores controllers through an evaluator, one outcome per controller.
  std::vector<CandidateOutcome> evaluate(std::span<const sim::ControllerConfig> controllers,
                                         BatchEvaluator& evaluator,
                                         std::int64_t record_every = 0) const;

  // The objective (minimised) of decision vector x, simulated on the calling thread. Throws
  // InputError, before simulating anything, when x has the wrong size, is not finite or lies
  // outside the tuning bounds.
  double objective(std::span<const double> x, const ObjectiveOptions& options = {}) const;

 private:
  std::shared_ptr<const Job> job_;
  std::shared_ptr<const sim::AnyPlant> plant_;
  SearchSpace space_;
  std::vector<double sim::ControllerConfig::*> members_;  // one per coordinate
};

// The problem as an optimiser sees it: the fitness of a batch of decision vectors, simulated
// through an evaluator. Counts the simulations it ran.
class ProblemFitness final : public BatchFitness {
 public:
  ProblemFitness(const TuningProblem& problem, BatchEvaluator& evaluator)
      : problem_(problem), evaluator_(evaluator) {}
  std::vector<double> operator()(const std::vector<Decision>& batch) override;
  std::int64_t simulations() const { return simulations_; }

 private:
  const TuningProblem& problem_;
  BatchEvaluator& evaluator_;
  std::int64_t simulations_ = 0;
};

}  // namespace ftc::tune
