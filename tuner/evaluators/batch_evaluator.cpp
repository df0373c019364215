#include "ftc/tune/evaluators/batch_evaluator.hpp"

#include <exception>

#include "ftc/tune/problem/problem.hpp"

namespace ftc::tune {

TaskResult run_task(const TuningProblem& problem, const SimulationBatch& batch, std::size_t k) {
  TaskResult r;
  const SimulationTask& task = batch.tasks[k];
  try {
    sim::SimulationResult s = problem.simulate(batch.candidates[task.candidate], task.scenario,
                                               task.record ? batch.record_every : 0);
    r.metrics = std::move(s.metrics);
    r.trajectory = std::move(s.trajectory);
  } catch (const std::exception& e) {
    r.error = e.what();
  } catch (...) {
    r.error = "unknown error";
  }
  return r;
}

std::vector<TaskResult> SerialEvaluator::run(const TuningProblem& problem,
                                             const SimulationBatch& batch) {
  std::vector<TaskResult> results;
  results.reserve(batch.tasks.size());
  for (std::size_t k = 0; k < batch.tasks.size(); ++k)
    results.push_back(run_task(problem, batch, k));
  return results;
}

}  // namespace ftc::tune
