#pragma once
// Uniform random search with the Bat algorithm's budget: M candidates drawn from U(lb, ub) at
// iteration 0 and at each of T iterations, M·(T+1) evaluations in all, keeping the best. It is
// the baseline that shows what the Bat algorithm's moves buy.
#include "ftc/tune/optimizer.hpp"
#include "ftc/tune/rng.hpp"

namespace ftc::tune {

class RandomSearch final : public Optimizer {
 public:
  RandomSearch(const AlgorithmConfig& config, std::uint64_t seed, const SearchSpace& space);

  void initialize(BatchEvaluator& evaluator) override;
  void iterate(BatchEvaluator& evaluator) override;
  int iteration() const override { return t_; }
  int iterations() const override { return config_.iterations; }
  const std::vector<HistoryRow>& history() const override { return history_; }
  nlohmann::json state() const override;
  void restore(const nlohmann::json& state) override;

 private:
  void generation(BatchEvaluator& evaluator);

  AlgorithmConfig config_;
  SearchSpace space_;
  Rng rng_;
  Decision best_;
  double best_fitness_ = 0.0;
  int t_ = -1;
  std::int64_t evaluations_ = 0;
  std::vector<HistoryRow> history_;
};

}  // namespace ftc::tune
