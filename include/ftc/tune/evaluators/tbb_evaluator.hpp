#pragma once
// Runs a batch as TBB tasks, one per simulation, inside an arena of its own with `threads`
// workers; each task writes its own slot, so the results do not depend on the thread count.
#include <memory>
#include <string>
#include <vector>

#include "ftc/tune/evaluators/batch_evaluator.hpp"

namespace ftc::tune {

class TbbEvaluator final : public BatchEvaluator {
 public:
  // threads <= 0: one per hardware thread.
  explicit TbbEvaluator(int threads = 0);
  ~TbbEvaluator() override;

  std::vector<TaskResult> run(const SimulationBatch& batch) override;
  int concurrency() const override;
  std::string name() const override { return "tbb"; }

 private:
  struct Arena;
  std::unique_ptr<Arena> arena_;
};

}  // namespace ftc::tune
