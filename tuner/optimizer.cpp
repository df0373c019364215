#include "ftc/tune/optimizer.hpp"

#include <cmath>
#include <limits>

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
                                 const IterationObserver& observer, const nlohmann::json* resume) {
  OptimizationResult r;
  bool go = true;
  if (resume) {
    optimizer.restore(*resume);
  } else {
    optimizer.initialize(evaluator);
    go = !observer || observer(optimizer.history().back(), optimizer);
  }
  while (go && optimizer.iteration() < optimizer.iterations()) {
    optimizer.iterate(evaluator);
    go = !observer || observer(optimizer.history().back(), optimizer);
  }
  const HistoryRow& last = optimizer.history().back();
  r.best = last.best;
  r.best_fitness = last.best_fitness;
  r.evaluations = last.evaluations;
  r.history = optimizer.history();
  r.completed = optimizer.iteration() == optimizer.iterations();
  return r;
}

nlohmann::json exact(double v) {
  return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr);
}

double exact_double(const nlohmann::json& j, double if_null) {
  return j.is_null() ? if_null : j.get<double>();
}

nlohmann::json to_json(const HistoryRow& row) {
  nlohmann::json best = nlohmann::json::array();
  for (double v : row.best) best.push_back(v);
  return {{"iteration", row.iteration},
          {"best_fitness", exact(row.best_fitness)},
          {"best", best},
          {"mean_loudness", exact(row.mean_loudness)},
          {"mean_pulse_rate", exact(row.mean_pulse_rate)},
          {"evaluations", row.evaluations}};
}

HistoryRow history_row_from_json(const nlohmann::json& j) {
  constexpr double nan = std::numeric_limits<double>::quiet_NaN();
  HistoryRow row;
  row.iteration = j.at("iteration").get<int>();
  row.best_fitness = exact_double(j.at("best_fitness"), std::numeric_limits<double>::infinity());
  row.best = j.at("best").get<std::vector<double>>();
  row.mean_loudness = exact_double(j.at("mean_loudness"), nan);
  row.mean_pulse_rate = exact_double(j.at("mean_pulse_rate"), nan);
  row.evaluations = j.at("evaluations").get<std::int64_t>();
  return row;
}

}  // namespace ftc::tune
