#include "ftc/tune/evaluators/tbb_evaluator.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <exception>
#include <limits>

namespace ftc::tune {

struct ParallelEvaluator::Arena {
  tbb::task_arena arena;
  explicit Arena(int threads)
      : arena(threads > 0 ? threads : tbb::this_task_arena::max_concurrency()) {}
};

ParallelEvaluator::ParallelEvaluator(const TuningProblem& problem, int threads)
    : problem_(problem), arena_(std::make_unique<Arena>(threads)) {}

ParallelEvaluator::~ParallelEvaluator() = default;

int ParallelEvaluator::threads() const { return arena_->arena.max_concurrency(); }

std::vector<CandidateOutcome> ParallelEvaluator::evaluate_controllers(
    const std::vector<sim::ControllerConfig>& controllers, std::int64_t record_every) {
  const std::size_t n = controllers.size(), S = problem_.scenarios();
  std::vector<sim::SimulationResult> results(n * S);
  std::vector<std::string> errors(n * S);

  // One task per (candidate, scenario); grain 1 because one task is a whole simulation.
  arena_->arena.execute([&] {
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n * S, 1),
                      [&](const tbb::blocked_range<std::size_t>& r) {
                        for (std::size_t k = r.begin(); k != r.end(); ++k) {
                          try {
                            results[k] = problem_.simulate(controllers[k / S], k % S, record_every);
                          } catch (const std::exception& e) {
                            errors[k] = e.what();
                          } catch (...) {
                            errors[k] = "unknown error";
                          }
                        }
                      });
  });
  simulations_ += static_cast<std::int64_t>(n * S);

  std::vector<CandidateOutcome> out(n);
  for (std::size_t i = 0; i < n; ++i) {
    std::vector<sim::Metrics> per;
    for (std::size_t s = 0; s < S; ++s) {
      per.push_back(std::move(results[i * S + s].metrics));
      if (record_every > 0) out[i].trajectories.push_back(std::move(results[i * S + s].trajectory));
    }
    out[i].evaluation = score(problem_.job().objective, std::move(per));
    for (std::size_t s = 0; s < S; ++s)
      if (!errors[i * S + s].empty()) {
        out[i].error = errors[i * S + s];
        out[i].evaluation.objective = std::numeric_limits<double>::infinity();
        out[i].evaluation.fitness = 0.0;
        break;
      }
  }
  return out;
}

std::vector<double> ParallelEvaluator::evaluate(const std::vector<Decision>& batch) {
  std::vector<sim::ControllerConfig> controllers;
  controllers.reserve(batch.size());
  for (const Decision& x : batch) controllers.push_back(problem_.controller_for(x));
  last_ = evaluate_controllers(controllers);
  std::vector<double> J(batch.size());
  for (std::size_t i = 0; i < batch.size(); ++i) J[i] = last_[i].evaluation.fitness;
  return J;
}

}  // namespace ftc::tune
