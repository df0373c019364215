#include "ftc/tune/optimizers/bat.hpp"

#include <cassert>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace ftc::tune {

Decision bat_frequency_move(const SearchSpace& space, const Decision& x, Decision& v,
                            const Decision& best, double f) {
  Decision c(x.size());
  for (std::size_t j = 0; j < x.size(); ++j) {
    v[j] += (best[j] - x[j]) * f;
    c[j] = space.clamp(j, x[j] + v[j]);
  }
  return c;
}

BatAlgorithm::BatAlgorithm(const AlgorithmConfig& config, std::uint64_t seed,
                           const SearchSpace& space)
    : GenerationalOptimizer(config, seed, space) {
  assert(config.type == AlgorithmType::bat);
  assert(space.dimension() > 0);
}

void BatAlgorithm::initialize(BatchEvaluator& evaluator) {
  const std::size_t d = space_.dimension();
  bats_.assign(static_cast<std::size_t>(config_.population), Bat{});
  std::vector<Decision> batch;
  for (Bat& b : bats_) {
    b.x.resize(d);
    b.v.resize(d);
    for (std::size_t j = 0; j < d; ++j) b.x[j] = rng_.uniform(space_.lower[j], space_.upper[j]);
    for (std::size_t j = 0; j < d; ++j) b.v[j] = rng_.uniform();
    b.loudness = config_.loudness;
    b.pulse_rate = config_.pulse_rate;
    batch.push_back(b.x);
  }
  const std::vector<double> J = evaluator.evaluate(batch);
  if (J.size() != bats_.size()) throw std::logic_error("evaluator returned a wrong-sized batch");
  evaluations_ += static_cast<std::int64_t>(J.size());
  std::size_t best = 0;
  for (std::size_t i = 0; i < bats_.size(); ++i) {
    bats_[i].fitness = J[i];
    if (J[i] > J[best]) best = i;
  }
  best_ = bats_[best].x;
  best_fitness_ = J[best];
  t_ = 0;
  record_iteration();
}

void BatAlgorithm::iterate(BatchEvaluator& evaluator) {
  assert(t_ >= 0 && "initialize() first");
  const int t = t_ + 1;
  const std::size_t d = space_.dimension();

  double mean_loudness = 0.0;
  for (const Bat& b : bats_) mean_loudness += b.loudness;
  mean_loudness /= static_cast<double>(bats_.size());

  const Decision best = best_;  // x* as it was at the start of the iteration
  std::vector<Decision> candidates;
  candidates.reserve(bats_.size());
  for (Bat& b : bats_) {
    const double f = config_.f_min + (config_.f_max - config_.f_min) * rng_.uniform();
    Decision c = bat_frequency_move(space_, b.x, b.v, best, f);
    if (rng_.uniform() > b.pulse_rate) {  // local random walk around the best (eq. 39)
      for (std::size_t j = 0; j < d; ++j)
        c[j] = space_.clamp(j, best[j] + rng_.uniform(-1.0, 1.0) * mean_loudness);
    }
    candidates.push_back(std::move(c));
  }

  const std::vector<double> J = evaluator.evaluate(candidates);
  if (J.size() != bats_.size()) throw std::logic_error("evaluator returned a wrong-sized batch");
  evaluations_ += static_cast<std::int64_t>(J.size());

  const double pulse = config_.pulse_rate * (1.0 - std::exp(-config_.pulse_rate_growth * t));
  for (std::size_t i = 0; i < bats_.size(); ++i) {
    Bat& b = bats_[i];
    if (rng_.uniform() < b.loudness && J[i] >= b.fitness) {
      b.x = candidates[i];
      b.fitness = J[i];
      b.loudness *= config_.loudness_decay;
      b.pulse_rate = pulse;
    }
    if (J[i] > best_fitness_) {
      best_ = candidates[i];
      best_fitness_ = J[i];
    }
  }
  t_ = t;
  record_iteration();
}

nlohmann::json BatAlgorithm::state() const {
  nlohmann::json s = common_state("bat");
  s["bats"] = nlohmann::json::array();
  for (const Bat& b : bats_)
    s["bats"].push_back({{"x", b.x},
                         {"v", b.v},
                         {"loudness", b.loudness},
                         {"pulse_rate", b.pulse_rate},
                         {"fitness", json_number(b.fitness)}});
  return s;
}

void BatAlgorithm::restore(const nlohmann::json& s) {
  restore_common(s, "bat");
  bats_.clear();
  for (const nlohmann::json& b : s.at("bats"))
    bats_.push_back({b.at("x").get<Decision>(), b.at("v").get<Decision>(),
                     b.at("loudness").get<double>(), b.at("pulse_rate").get<double>(),
                     json_number_or(b.at("fitness"), std::numeric_limits<double>::infinity())});
}

void BatAlgorithm::record_iteration() {
  double loudness = 0.0, pulse_rate = 0.0;
  for (const Bat& b : bats_) {
    loudness += b.loudness;
    pulse_rate += b.pulse_rate;
  }
  const double n = static_cast<double>(bats_.size());
  record(loudness / n, pulse_rate / n);
}

}  // namespace ftc::tune
