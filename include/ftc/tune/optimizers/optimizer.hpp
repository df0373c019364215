#pragma once
// Population optimisers that maximise fitness over a SearchSpace, one generation at a time:
// initialize() evaluates the first population (iteration 0), iterate() one further generation.
// All random numbers are drawn on the calling thread in a fixed order, so a run is determined by
// its settings and seed, whatever the evaluator does in parallel.
#include <cstdint>
#include <functional>
#include <memory>
#include <nlohmann/json.hpp>
#include <vector>

#include "ftc/tune/evaluators/batch_evaluator.hpp"
#include "ftc/tune/job/job.hpp"
#include "ftc/tune/optimizers/rng.hpp"
#include "ftc/tune/optimizers/search_space.hpp"

namespace ftc::tune {

struct HistoryRow {
  int iteration = 0;             // 0 = the initial population
  double best_fitness = 0.0;     // J(x*) after this iteration
  Decision best;                 // x*
  double mean_loudness = 0.0;    // Bat algorithm only (NaN for random search)
  double mean_pulse_rate = 0.0;  // Bat algorithm only (NaN for random search)
  std::int64_t evaluations = 0;  // so far
};

struct OptimizationResult {
  Decision best;
  double best_fitness = 0.0;
  std::vector<HistoryRow> history;
  std::int64_t evaluations = 0;
  bool completed = false;  // false when the observer stopped the run early
};

class Optimizer {
 public:
  virtual ~Optimizer() = default;
  virtual void initialize(BatchEvaluator& evaluator) = 0;
  virtual void iterate(BatchEvaluator& evaluator) = 0;
  virtual int iteration() const = 0;   // completed iterations (0 after initialize)
  virtual int iterations() const = 0;  // T
  virtual const std::vector<HistoryRow>& history() const = 0;

  // The complete state after the last iteration, random-number engine included, as JSON with
  // exact (round-trip) doubles. restore() continues from it exactly as if never interrupted.
  virtual nlohmann::json state() const = 0;
  virtual void restore(const nlohmann::json& state) = 0;
};

std::unique_ptr<Optimizer> make_optimizer(const AlgorithmConfig& config, std::uint64_t seed,
                                          const SearchSpace& space);

// Called after every iteration (including 0); returning false stops the run. The optimizer is
// passed so that a caller can checkpoint its state().
using IterationObserver = std::function<bool(const HistoryRow&, const Optimizer&)>;

// Runs to the last iteration or until the observer says stop. With `resume` (a state() saved
// earlier) it continues from there instead of initialising.
OptimizationResult run_optimizer(Optimizer& optimizer, BatchEvaluator& evaluator,
                                 const IterationObserver& observer = {},
                                 const nlohmann::json* resume = nullptr);

// What the population optimisers here have in common: settings, search space, random engine,
// iteration and evaluation counters, the best point and the history, and the checkpoint of all
// that. A subclass adds its own population state to state() and restore().
class GenerationalOptimizer : public Optimizer {
 public:
  int iteration() const override { return t_; }
  int iterations() const override { return config_.iterations; }
  const std::vector<HistoryRow>& history() const override { return history_; }

 protected:
  GenerationalOptimizer(const AlgorithmConfig& config, std::uint64_t seed, const SearchSpace& space)
      : config_(config), space_(space), rng_(seed) {}

  // Appends the history row of iteration t_ (NaN loudness and pulse rate where meaningless).
  void record(double mean_loudness, double mean_pulse_rate);
  // The common part of a checkpoint, tagged with the algorithm's name, and its inverse
  // (which refuses another algorithm's checkpoint).
  nlohmann::json common_state(const char* algorithm) const;
  void restore_common(const nlohmann::json& state, const char* algorithm);

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
