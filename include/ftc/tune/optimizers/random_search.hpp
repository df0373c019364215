#pragma once
// Uniform random search with the Bat algorithm's budget: M candidates drawn from U(lb, ub) at
// iteration 0 and at each of T iterations, M·(T+1) evaluations in all, keeping the best. It is
// the baseline that shows what the Bat algorithm's moves buy.
#include "ftc/tune/optimizers/optimizer.hpp"

namespace ftc::tune {

class RandomSearch final : public GenerationalOptimizer {
 public:
  RandomSearch(const AlgorithmConfig& config, std::uint64_t seed, const SearchSpace& space);

  void initialize(BatchEvaluator& evaluator) override;
  void iterate(BatchEvaluator& evaluator) override;
  nlohmann::json state() const override;
  void restore(const nlohmann::json& state) override;

 private:
  void generation(BatchEvaluator& evaluator);
};

}  // namespace ftc::tune
