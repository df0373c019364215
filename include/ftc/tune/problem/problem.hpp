#pragma once
// The tuning problem of a job: a decision vector names values of the controller fields listed
// under tuning.parameters; a candidate is scored by simulating every scenario of the job and
// taking the objective of SPEC §6 (metric in the window, aggregated over scenarios); fitness
// J = 1/objective, 0 when a scenario diverged. Immutable after construction, so any number of
// threads may evaluate candidates at once.
#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "ftc/sim/controller_config.hpp"
#include "ftc/sim/metrics.hpp"
#include "ftc/sim/plants.hpp"
#include "ftc/tune/problem/evaluation.hpp"
#include "ftc/tune/job/job.hpp"
#include "ftc/tune/optimizers/search_space.hpp"

namespace ftc::tune {

class TuningProblem {
 public:
  // Throws InputError when the job has no tuning section or does not validate.
  explicit TuningProblem(Job job);

  const Job& job() const { return job_; }
  const sim::AnyPlant& plant() const { return *plant_; }
  const SearchSpace& space() const { return space_; }
  std::size_t scenarios() const { return job_.scenarios.size(); }

  // The job's controller with the tuned fields set from x (in space().names order).
  sim::ControllerConfig controller_for(std::span<const double> x) const;
  // One scenario with one controller. Never throws for a diverging run.
  // record_every > 0 also keeps every k-th sample of the trajectory.
  sim::SimulationResult simulate(const sim::ControllerConfig& controller, std::size_t scenario,
                                 std::int64_t record_every = 0) const;

 private:
  Job job_;
  std::shared_ptr<const sim::AnyPlant> plant_;
  SearchSpace space_;
  std::vector<double sim::ControllerConfig::*> members_;  // one per coordinate
};

}  // namespace ftc::tune
