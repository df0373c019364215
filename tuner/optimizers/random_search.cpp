#include "ftc/tune/optimizers/random_search.hpp"

#include <algorithm>
#include <stdexcept>

namespace ftc::tune {

namespace {

std::shared_ptr<const schema::Object<RandomSearchSettings>> random_shape() {
  using S = RandomSearchSettings;
  static const auto shape = std::make_shared<const schema::Object<S>>(
      schema::Object<S>("Uniform random search: M candidates per iteration, M·(T+1) in all")
          .integer("population", &S::population, schema::IntRange{1, 100000},
                   "candidates per iteration M")
          .integer("iterations", &S::iterations, schema::IntRange{0, 100000},
                   "iterations T after the first"));
  return shape;
}

}  // namespace

std::vector<FieldError> RandomSearchSettings::validate(const std::string& path) const {
  std::vector<FieldError> errs;
  random_shape()->validate(*this, path, errs);
  return errs;
}

AlgorithmInfo random_search_info() {
  return struct_algorithm<RandomSearchSettings>(
      "random", "uniform random search, the baseline", random_shape(),
      [](const RandomSearchSettings& s, std::uint64_t seed, const SearchSpace& space) {
        return std::make_unique<RandomSearch>(s, seed, space);
      });
}

AlgorithmPtr random_search_like(const AlgorithmSettings& other) {
  RandomSearchSettings s;
  s.population = other.population();
  // Whole generations within the other's budget, at least one.
  s.iterations = static_cast<int>(std::max<std::int64_t>(
      0, other.evaluations() / std::max(1, other.population()) - 1));
  // Parsed by the registry's entry, so that it is in the registry's form: one that also
  // searches for fronts, which a job of two or more soft goals needs (a run of one objective
  // does not change by a bit: the front form forwards everything else).
  const AlgorithmInfo* info = find_algorithm("random");
  std::vector<FieldError> errs;
  AlgorithmPtr a = info ? info->parse(nlohmann::json{{"type", "random"},
                                                     {"population", s.population},
                                                     {"iterations", s.iterations}},
                                      "/tuning/algorithm", errs)
                        : nullptr;
  throw_if_errors("algorithm", std::move(errs));
  if (!a) throw std::logic_error("random search is not in the algorithm registry");
  return a;
}

RandomSearch::RandomSearch(const RandomSearchSettings& settings, std::uint64_t seed,
                           const SearchSpace& space)
    : GenerationalOptimizer(settings.iterations, seed, space), settings_(settings) {}

void RandomSearch::generation(BatchFitness& fitness) {
  std::vector<Decision> batch(static_cast<std::size_t>(settings_.population));
  for (Decision& x : batch) {
    x.resize(space_.dimension());
    for (std::size_t j = 0; j < x.size(); ++j)
      x[j] = rng_.uniform(space_.lower[j], space_.upper[j]);
  }
  // A candidate is kept only above the best so far, so that is its cap (none before the first).
  const std::vector<double> caps(batch.size(), best_.empty() ? kNoCap : best_fitness_);
  const std::vector<double> J = evaluate(fitness, batch, caps);
  for (std::size_t i = 0; i < batch.size(); ++i)
    if (best_.empty() || J[i] > best_fitness_) {
      best_ = batch[i];
      best_fitness_ = J[i];
    }
  record();
}

nlohmann::json RandomSearch::state() const { return common_state("random"); }

void RandomSearch::restore(const nlohmann::json& s) {
  restore_common(s, "random", settings_.population, 0, true);
}

void RandomSearch::initialize(BatchFitness& fitness) {
  t_ = 0;
  generation(fitness);
}

void RandomSearch::iterate(BatchFitness& fitness) {
  ++t_;
  generation(fitness);
}

}  // namespace ftc::tune
