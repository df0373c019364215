#pragma once
// Evaluates batches of candidates of a TuningProblem in parallel: one task per candidate ×
// scenario pair, each writing its metrics into its own slot, then a serial pass that scores the
// candidates in order. Runs inside its own arena of `threads` workers. A candidate that diverges
// or throws gets J = 0; nothing escapes the batch. Results do not depend on the thread count.
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "ftc/tune/evaluators/batch_evaluator.hpp"
#include "ftc/tune/problem/evaluation.hpp"
#include "ftc/tune/problem/problem.hpp"

namespace ftc::tune {

struct CandidateOutcome {
  Evaluation evaluation;  // per-scenario metrics, objective, fitness
  std::string error;      // non-empty when a simulation threw (fitness is then 0)
  std::vector<sim::Trajectory> trajectories;  // per scenario, when recorded
};

class ParallelEvaluator final : public BatchEvaluator {
 public:
  // threads <= 0: one per hardware thread.
  ParallelEvaluator(const TuningProblem& problem, int threads);
  ~ParallelEvaluator() override;

  std::vector<double> evaluate(const std::vector<Decision>& batch) override;
  // The same machinery for arbitrary controllers (comparisons, baselines); record_every > 0
  // also keeps their trajectories (every k-th sample).
  std::vector<CandidateOutcome> evaluate_controllers(
      const std::vector<sim::ControllerConfig>& controllers, std::int64_t record_every = 0);

  int threads() const;
  const std::vector<CandidateOutcome>& last_batch() const { return last_; }
  std::int64_t simulations() const { return simulations_; }

 private:
  struct Arena;
  const TuningProblem& problem_;
  std::unique_ptr<Arena> arena_;
  std::vector<CandidateOutcome> last_;
  std::int64_t simulations_ = 0;
};

}  // namespace ftc::tune
