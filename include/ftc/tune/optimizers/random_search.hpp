#pragma once
// Uniform random search: M candidates drawn from U(lb, ub) at iteration 0 and at each of T
// iterations, M·(T+1) evaluations in all, keeping the best. It is the baseline that shows what an
// algorithm's moves buy (`ftctune run --baseline` runs it with the job's budget and seed).
#include <string>
#include <vector>

#include "ftc/tune/optimizers/optimizer.hpp"

namespace ftc::tune {

struct RandomSearchSettings {
  int population = 10;  // M
  int iterations = 10;  // T

  std::vector<FieldError> validate(const std::string& path = "") const;
};

class RandomSearch final : public GenerationalOptimizer {
 public:
  RandomSearch(const RandomSearchSettings& settings, std::uint64_t seed, const SearchSpace& space);

  void initialize(BatchFitness& fitness) override;
  void iterate(BatchFitness& fitness) override;
  nlohmann::json state() const override;
  void restore(const nlohmann::json& state) override;

 private:
  void generation(BatchFitness& fitness);

  RandomSearchSettings settings_;
};

// The registry entry ("random").
AlgorithmInfo random_search_info();
// Random search with the population and budget of another algorithm's settings.
AlgorithmPtr random_search_like(const AlgorithmSettings& other);

}  // namespace ftc::tune
