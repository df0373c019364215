#include "ftc/tune/evaluators/tbb_evaluator.hpp"

#include <atomic>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

namespace ftc::tune {

struct TbbEvaluator::Arena {
  tbb::task_arena arena;
  explicit Arena(int threads)
      : arena(threads > 0 ? threads : tbb::this_task_arena::max_concurrency()) {}
};

TbbEvaluator::TbbEvaluator(int threads) : arena_(std::make_unique<Arena>(threads)) {}
TbbEvaluator::~TbbEvaluator() = default;

int TbbEvaluator::concurrency() const { return arena_->arena.max_concurrency(); }

std::vector<TaskResult> TbbEvaluator::run(const SimulationBatch& batch) {
  std::vector<TaskResult> results(batch.tasks.size());
  const std::vector<std::vector<std::size_t>> packs = plan_packs(batch, concurrency());
  // Once the interrupt is seen, no other pack starts (a flag, not TBB's cancellation, so that
  // the packs under way end normally and nothing is thrown across the arena).
  std::atomic<bool> stop{false};
  // Grain 1: one pack is up to W whole simulations in SIMD lanes.
  arena_->arena.execute([&] {
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, packs.size(), 1),
                      [&](const tbb::blocked_range<std::size_t>& r) {
                        for (std::size_t p = r.begin(); p != r.end(); ++p) {
                          if (stop.load(std::memory_order_relaxed)) return;
                          if (interrupted()) {
                            stop.store(true, std::memory_order_relaxed);
                            return;
                          }
                          run_pack(batch, packs[p], results);
                        }
                      });
  });
  if (stop.load()) throw Interrupted();
  return results;
}

}  // namespace ftc::tune
