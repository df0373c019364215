#pragma once
// The evaluator seam. A batch evaluator runs a flat list of simulation tasks, each one
// candidate controller on one scenario of a tuning problem, and returns their results by task
// index. How (on the calling thread, on TBB workers, on other machines) is its own business:
// the problem builds the tasks and scores the results, the optimiser never sees either. A task
// that fails (a controller with invalid values) is a result with an error, never an exception.
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "ftc/sim/controller_config.hpp"
#include "ftc/sim/metrics.hpp"
#include "ftc/sim/simulation.hpp"

namespace ftc::tune {

class TuningProblem;

struct SimulationTask {
  std::size_t candidate = 0;  // index into SimulationBatch::candidates
  std::size_t scenario = 0;   // index into the problem's scenarios
  bool record = false;        // keep the trajectory (every record_every-th sample)
};

struct SimulationBatch {
  std::span<const sim::ControllerConfig> candidates;
  std::span<const SimulationTask> tasks;
  std::int64_t record_every = 0;  // > 0: keep every k-th sample of each trajectory
};

struct TaskResult {
  sim::Metrics metrics;
  sim::Trajectory trajectory;  // when recorded
  std::string error;           // non-empty when the simulation could not run
};

class BatchEvaluator {
 public:
  virtual ~BatchEvaluator() = default;
  // One result per task, in task order.
  virtual std::vector<TaskResult> run(const TuningProblem& problem,
                                      const SimulationBatch& batch) = 0;
  // Simulations it can run at once (threads); for run.json and progress lines.
  virtual int concurrency() const = 0;
  // Threads on each process taking part (one entry unless the evaluator spans processes).
  virtual std::vector<int> threads_per_rank() const { return {concurrency()}; }
  virtual std::string name() const = 0;
};

// Task k of a batch, as every evaluator must run it: the problem's simulation, with an exception
// turned into the task's error.
TaskResult run_task(const TuningProblem& problem, const SimulationBatch& batch, std::size_t k);

// Tasks batch.tasks[k] for k in `pack`, in the plant's SIMD lanes (sim::AnyPlant::
// simulate_pack), into results[k]; each result is what run_task gives, to the last bit.
void run_pack(const TuningProblem& problem, const SimulationBatch& batch,
              std::span<const std::size_t> pack, std::span<TaskResult> results);

// The batch's tasks in packs for run_pack: tasks that can share lanes (same sample time,
// substeps and duration) go together, in task order, at most the plant's pack width to a pack;
// when that leaves fewer packs than `workers`, the packs are made smaller so that every worker
// gets one. Lanes give the same bits however tasks are packed, so this only affects speed.
std::vector<std::vector<std::size_t>> plan_packs(const TuningProblem& problem,
                                                 const SimulationBatch& batch, int workers);

// Runs the tasks one after another on the calling thread (tests, embedding, debugging).
class SerialEvaluator final : public BatchEvaluator {
 public:
  std::vector<TaskResult> run(const TuningProblem& problem, const SimulationBatch& batch) override;
  int concurrency() const override { return 1; }
  std::string name() const override { return "serial"; }
};

}  // namespace ftc::tune
