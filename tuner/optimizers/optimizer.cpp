#include "ftc/tune/optimizers/optimizer.hpp"

#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include "ftc/tune/optimizers/bat.hpp"
#include "ftc/tune/optimizers/random_search.hpp"

namespace ftc::tune {

namespace {

nlohmann::json to_json(const HistoryRow& row) {
  nlohmann::json best = nlohmann::json::array();
  for (double v : row.best) best.push_back(v);
  return {{"iteration", row.iteration},
          {"best_fitness", json_number(row.best_fitness)},
          {"best", best},
          {"mean_loudness", json_number(row.mean_loudness)},
          {"mean_pulse_rate", json_number(row.mean_pulse_rate)},
          {"evaluations", row.evaluations}};
}

HistoryRow history_row_from_json(const nlohmann::json& j) {
  constexpr double nan = std::numeric_limits<double>::quiet_NaN();
  HistoryRow row;
  row.iteration = j.at("iteration").get<int>();
  row.best_fitness = json_number_or(j.at("best_fitness"), std::numeric_limits<double>::infinity());
  row.best = j.at("best").get<std::vector<double>>();
  row.mean_loudness = json_number_or(j.at("mean_loudness"), nan);
  row.mean_pulse_rate = json_number_or(j.at("mean_pulse_rate"), nan);
  row.evaluations = j.at("evaluations").get<std::int64_t>();
  return row;
}

}  // namespace

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

void GenerationalOptimizer::record(double mean_loudness, double mean_pulse_rate) {
  HistoryRow row;
  row.iteration = t_;
  row.best_fitness = best_fitness_;
  row.best = best_;
  row.mean_loudness = mean_loudness;
  row.mean_pulse_rate = mean_pulse_rate;
  row.evaluations = evaluations_;
  history_.push_back(std::move(row));
}

nlohmann::json GenerationalOptimizer::common_state(const char* algorithm) const {
  nlohmann::json history = nlohmann::json::array();
  for (const HistoryRow& h : history_) history.push_back(to_json(h));
  return {{"algorithm", algorithm}, {"t", t_},       {"evaluations", evaluations_},
          {"rng", rng_.save()},     {"best", best_}, {"best_fitness", json_number(best_fitness_)},
          {"history", history}};
}

void GenerationalOptimizer::restore_common(const nlohmann::json& s, const char* algorithm) {
  if (s.at("algorithm") != algorithm)
    throw std::invalid_argument(std::string("checkpoint is not a state of the ") + algorithm +
                                " optimiser");
  t_ = s.at("t").get<int>();
  evaluations_ = s.at("evaluations").get<std::int64_t>();
  rng_.load(s.at("rng").get<std::string>());
  best_ = s.at("best").get<Decision>();
  best_fitness_ = json_number_or(s.at("best_fitness"), std::numeric_limits<double>::infinity());
  history_.clear();
  for (const nlohmann::json& h : s.at("history")) history_.push_back(history_row_from_json(h));
}

}  // namespace ftc::tune
