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
  HistoryRow row;
  row.iteration = t_;
  row.best_fitness = best_fitness_;
  row.best = best_;
  row.mean_loudness = std::numeric_limits<double>::quiet_NaN();
  row.mean_pulse_rate = std::numeric_limits<double>::quiet_NaN();
  row.evaluations = evaluations_;
  history_.push_back(std::move(row));
}

nlohmann::json RandomSearch::state() const {
  nlohmann::json history = nlohmann::json::array();
  for (const HistoryRow& h : history_) history.push_back(to_json(h));
  return {{"algorithm", "random"}, {"t", t_},       {"evaluations", evaluations_},
          {"rng", rng_.save()},    {"best", best_}, {"best_fitness", exact(best_fitness_)},
          {"history", history}};
}

void RandomSearch::restore(const nlohmann::json& s) {
  if (s.at("algorithm") != "random")
    throw std::invalid_argument("checkpoint is not a random-search state");
  t_ = s.at("t").get<int>();
  evaluations_ = s.at("evaluations").get<std::int64_t>();
  rng_.load(s.at("rng").get<std::string>());
  best_ = s.at("best").get<Decision>();
  best_fitness_ = exact_double(s.at("best_fitness"), std::numeric_limits<double>::infinity());
  history_.clear();
  for (const nlohmann::json& h : s.at("history")) history_.push_back(history_row_from_json(h));
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
