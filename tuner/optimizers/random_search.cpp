#include "ftc/tune/optimizers/random_search.hpp"

#include <limits>
#include <stdexcept>

namespace ftc::tune {

RandomSearch::RandomSearch(const AlgorithmConfig& config, std::uint64_t seed,
                           const SearchSpace& space)
    : GenerationalOptimizer(config, seed, space) {}

void RandomSearch::generation(BatchEvaluator& evaluator) {
  std::vector<Decision> batch(static_cast<std::size_t>(config_.population));
  for (Decision& x : batch) {
    x.resize(space_.dimension());
    for (std::size_t j = 0; j < x.size(); ++j)
      x[j] = rng_.uniform(space_.lower[j], space_.upper[j]);
  }
  const std::vector<double> J = evaluator.evaluate(batch);
  if (J.size() != batch.size()) throw std::logic_error("evaluator returned a wrong-sized batch");
  evaluations_ += static_cast<std::int64_t>(J.size());
  for (std::size_t i = 0; i < batch.size(); ++i)
    if (best_.empty() || J[i] > best_fitness_) {
      best_ = batch[i];
      best_fitness_ = J[i];
    }
  constexpr double nan = std::numeric_limits<double>::quiet_NaN();  // no loudness, no pulses
  record(nan, nan);
}

nlohmann::json RandomSearch::state() const { return common_state("random"); }

void RandomSearch::restore(const nlohmann::json& s) { restore_common(s, "random"); }

void RandomSearch::initialize(BatchEvaluator& evaluator) {
  t_ = 0;
  generation(evaluator);
}

void RandomSearch::iterate(BatchEvaluator& evaluator) {
  ++t_;
  generation(evaluator);
}

}  // namespace ftc::tune
