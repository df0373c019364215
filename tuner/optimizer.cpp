#include "ftc/tune/optimizer.hpp"

#include "ftc/tune/bat_algorithm.hpp"
#include "ftc/tune/random_search.hpp"

namespace ftc::tune {

std::unique_ptr<Optimizer> make_optimizer(const AlgorithmConfig& config, std::uint64_t seed,
                                          const SearchSpace& space) {
  if (config.type == AlgorithmType::random)
    return std::make_unique<RandomSearch>(config, seed, space);
  return std::make_unique<BatAlgorithm>(config, seed, space);
}

OptimizationResult run_optimizer(Optimizer& optimizer, BatchEvaluator& evaluator,
                                 const IterationObserver& observer) {
  OptimizationResult r;
  optimizer.initialize(evaluator);
  bool go = !observer || observer(optimizer.history().back());
  while (go && optimizer.iteration() < optimizer.iterations()) {
    optimizer.iterate(evaluator);
    go = !observer || observer(optimizer.history().back());
  }
  const HistoryRow& last = optimizer.history().back();
  r.best = last.best;
  r.best_fitness = last.best_fitness;
  r.evaluations = last.evaluations;
  r.history = optimizer.history();
  r.completed = optimizer.iteration() == optimizer.iterations();
  return r;
}

}  // namespace ftc::tune
