#pragma once
// The evaluator seam. A batch evaluator runs a flat list of simulation tasks and returns their
// results by task index. Each task names what it simulates: a candidate controller of the batch
// and a scenario of the batch's SimulationSet (the plant and its scenarios, each with its
// simulation options), and whether to keep the trajectory. The evaluator knows nothing of who
// built the tasks: a TuningProblem builds them for its candidates and scores the results, a
// test or another tool can build its own. How the tasks run (on the calling thread, on TBB
// workers, on other machines) is the evaluator's business; the results are the same bits. A
// task that fails (a controller with invalid values) is a result with an error, never an
// exception.
#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

#include "ftc/sim/controller_config.hpp"
#include "ftc/sim/metrics.hpp"
#include "ftc/sim/plants.hpp"
#include "ftc/sim/scenario.hpp"
#include "ftc/sim/simulation.hpp"

namespace ftc::tune {

// What a batch's tasks index into: one plant and its scenarios, each with the options it is
// simulated with (its windows; record_every comes with the batch). Owned by whoever builds the
// batch (a TuningProblem holds one for its scenarios); immutable, so any number of threads may
// read it.
class SimulationSet {
 public:
  // Builds the plant (sim::make_plant: InputError for an unknown model or bad values); throws
  // std::invalid_argument unless there are as many options as scenarios.
  SimulationSet(sim::PlantSpec plant, std::vector<sim::Scenario> scenarios,
                std::vector<sim::SimulationOptions> options);

  const sim::PlantSpec& plant_spec() const { return spec_; }
  const sim::AnyPlant& plant() const { return *plant_; }
  std::size_t size() const { return scenarios_.size(); }
  const sim::Scenario& scenario(std::size_t i) const { return scenarios_[i]; }
  const sim::SimulationOptions& options(std::size_t i) const { return options_[i]; }
  // Tells sets apart without comparing them: every set has its own (copies share it). An
  // evaluator that ships the set to other processes sends it again only when this changes.
  std::uint64_t identity() const { return identity_; }
  // Other scenarios (and their options) on the same plant, which is shared, not built again.
  SimulationSet with_scenarios(std::vector<sim::Scenario> scenarios,
                               std::vector<sim::SimulationOptions> options) const;

 private:
  SimulationSet(sim::PlantSpec spec, std::shared_ptr<const sim::AnyPlant> plant,
                std::vector<sim::Scenario> scenarios, std::vector<sim::SimulationOptions> options);
  sim::PlantSpec spec_;
  std::shared_ptr<const sim::AnyPlant> plant_;
  std::vector<sim::Scenario> scenarios_;
  std::vector<sim::SimulationOptions> options_;
  std::uint64_t identity_ = 0;
};

struct SimulationTask {
  std::size_t candidate = 0;  // index into SimulationBatch::candidates
  std::size_t scenario = 0;   // index into SimulationBatch::set
  bool record = false;        // keep the trajectory (every record_every-th sample)
};

struct SimulationBatch {
  const SimulationSet& set;
  std::span<const sim::ControllerConfig> candidates;
  std::span<const SimulationTask> tasks;
  std::int64_t record_every = 0;  // > 0: keep every k-th sample of a recorded task's trajectory
};

struct TaskResult {
  sim::Metrics metrics;
  sim::Trajectory trajectory;  // when recorded
  std::string error;           // non-empty when the simulation could not run
  // For a plant whose model holds only in part of the state space (SimulationResult): whether
  // the run left it. Kept for recorded tasks, which run on the coordinating process under MPI.
  std::optional<bool> model_invalid;
};

// What run() throws when its interrupt asks it to stop: the batch has no results.
struct Interrupted : std::runtime_error {
  Interrupted() : std::runtime_error("the batch was interrupted") {}
};

class BatchEvaluator {
 public:
  virtual ~BatchEvaluator() = default;
  // One result per task, in task order.
  virtual std::vector<TaskResult> run(const SimulationBatch& batch) = 0;
  // A stop asked for while a batch runs (a cancelled job in the service): the TBB and
  // serial evaluators ask `interrupt` before each pack and, once it says true, start no other
  // pack and throw Interrupted when the running ones end, so a stop waits for a pack (up to W
  // simulations in lanes), not a batch. It is asked from worker threads, often: it must be
  // cheap and thread-safe (an atomic flag). Empty: never asked. An evaluator that cannot stop
  // within a batch (MPI) finishes it.
  void set_interrupt(std::function<bool()> interrupt) { interrupt_ = std::move(interrupt); }
  bool interrupted() const { return interrupt_ && interrupt_(); }
  // Simulations it can run at once (threads); for run.json and progress lines.
  virtual int concurrency() const = 0;
  // Threads on each process taking part (one entry unless the evaluator spans processes).
  virtual std::vector<int> threads_per_rank() const { return {concurrency()}; }
  virtual std::string name() const = 0;

 private:
  std::function<bool()> interrupt_;
};

// The options task k runs with: its scenario's, recording when the task asks to.
sim::SimulationOptions task_options(const SimulationBatch& batch, std::size_t k);

// Task k of a batch, as every evaluator must run it: the set's plant simulating the task's
// candidate on its scenario (AnyPlant::simulate), with an exception turned into the task's error.
TaskResult run_task(const SimulationBatch& batch, std::size_t k);

// Tasks batch.tasks[k] for k in `pack`, in the plant's SIMD lanes (sim::AnyPlant::
// simulate_pack), into results[k]; each result is what run_task gives, to the last bit.
void run_pack(const SimulationBatch& batch, std::span<const std::size_t> pack,
              std::span<TaskResult> results);

// The batch's tasks in packs for run_pack: tasks that can share lanes (same sample time,
// substeps and duration) go together, ordered by scenario (stable: candidates of one scenario
// share its inputs' tables), at most the plant's pack width to a pack;
// when that leaves fewer packs than `workers`, the packs are made smaller so that every worker
// gets one. Lanes give the same bits however tasks are packed, so this only affects speed.
std::vector<std::vector<std::size_t>> plan_packs(const SimulationBatch& batch, int workers);

// Runs the tasks one after another on the calling thread (tests, embedding, debugging).
class SerialEvaluator final : public BatchEvaluator {
 public:
  std::vector<TaskResult> run(const SimulationBatch& batch) override;
  int concurrency() const override { return 1; }
  std::string name() const override { return "serial"; }
};

}  // namespace ftc::tune
