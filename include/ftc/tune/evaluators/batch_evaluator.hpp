#pragma once
// What an optimiser needs from the outside world: the fitness (larger is better) of a batch of
// candidates, returned by index. How the batch is evaluated — serially, on TBB threads, or on
// other machines — is the evaluator's business; the optimiser never sees it.
#include <functional>
#include <utility>
#include <vector>

#include "ftc/tune/optimizers/search_space.hpp"

namespace ftc::tune {

class BatchEvaluator {
 public:
  virtual ~BatchEvaluator() = default;
  // One fitness per candidate, in order. A candidate that cannot be evaluated gets 0; the
  // evaluator does not throw for it.
  virtual std::vector<double> evaluate(const std::vector<Decision>& batch) = 0;
};

// Evaluates a plain fitness function on the calling thread (tests, small problems).
class FunctionEvaluator final : public BatchEvaluator {
 public:
  explicit FunctionEvaluator(std::function<double(const Decision&)> fitness)
      : fitness_(std::move(fitness)) {}

  std::vector<double> evaluate(const std::vector<Decision>& batch) override {
    std::vector<double> out;
    out.reserve(batch.size());
    for (const Decision& x : batch) out.push_back(fitness_(x));
    return out;
  }

 private:
  std::function<double(const Decision&)> fitness_;
};

}  // namespace ftc::tune
