#include "ftc/tune/random_search.hpp"

#include <limits>
#include <stdexcept>

namespace ftc::tune {

RandomSearch::RandomSearch(const AlgorithmConfig& config, std::uint64_t seed,
                           const SearchSpace& space)
    : config_(config), space_(space), rng_(seed) {}

void RandomSearch::generation(BatchEvaluator& evaluator) {
  std::vector<Decision> batch(static_cast<std::size_t>(config_.population));
  for (Decision& x : batch) {
    x.resize(space_.dimension());
    for (std::size_t j = 0; j < x.size(); ++j) x[j] = rng_.uniform(space_.lower[j], space_.upper[j]);
  }
  const std::vector<double> J = evaluator.evaluate(batch);
  if (J.size() != batch.size()) throw std::logic_error("evaluator returned a wrong-sized batch");
  evaluations_ += static_cast<std::int64_t>(J.size());
  for (std::size_t i = 0; i < batch.size(); ++i)
    if (best_.empty() || J[i] > best_fitness_) {
      best_ = batch[i];
      best_fitness_ = J[i];
    }
  HistoryRow row;
  row.iteration = t_;
  row.best_fitness = best_fitness_;
  row.best = best_;
  row.mean_loudness = std::numeric_limits<double>::quiet_NaN();
  row.mean_pulse_rate = std::numeric_limits<double>::quiet_NaN();
  row.evaluations = evaluations_;
  history_.push_back(std::move(row));
}

void RandomSearch::initialize(BatchEvaluator& evaluator) {
  t_ = 0;
  generation(evaluator);
}

void RandomSearch::iterate(BatchEvaluator& evaluator) {
  ++t_;
  generation(evaluator);
}

}  // namespace ftc::tune
