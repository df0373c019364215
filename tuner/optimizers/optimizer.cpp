#include "ftc/tune/optimizers/optimizer.hpp"

#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include "ftc/runtime/json_reader.hpp"
#include "ftc/tune/optimizers/state_check.hpp"

namespace ftc::tune {

using json_io::json_number;
using json_io::json_number_or;
using nlohmann::json;

namespace {

json to_json(const HistoryRow& row) {
  json extras = json::array();
  for (const auto& [name, value] : row.extras) extras.push_back({name, json_number(value)});
  return {{"iteration", row.iteration},
          {"best_fitness", json_number(row.best_fitness)},
          {"best", row.best},
          {"evaluations", row.evaluations},
          {"extras", extras}};
}

// One history row of a checkpoint, every field checked: the iteration, the evaluations so far
// (within [lo, hi]), the best point (inside the space when `bounded`) and the extra figures.
HistoryRow history_row_from_json(const json& j, const std::string& path, int iteration,
                                 std::int64_t lo, std::int64_t hi, const SearchSpace& space,
                                 bool bounded) {
  namespace sc = state_check;
  constexpr double nan = std::numeric_limits<double>::quiet_NaN();
  HistoryRow row;
  row.iteration = static_cast<int>(
      sc::integer(sc::member(j, path, "iteration"), path + "/iteration", iteration, iteration));
  row.best_fitness = sc::fitness(sc::member(j, path, "best_fitness"), path + "/best_fitness");
  row.best = sc::decision(sc::member(j, path, "best"), path + "/best", space, bounded);
  row.evaluations = sc::integer(sc::member(j, path, "evaluations"), path + "/evaluations", lo, hi);
  if (j.contains("extras")) {
    const json& extras = j.at("extras");
    if (!extras.is_array()) sc::fail(path + "/extras", "expected an array");
    for (std::size_t k = 0; k < extras.size(); ++k) {
      const std::string at = path + "/extras/" + std::to_string(k);
      const json& e = sc::array(extras[k], at, 2);
      if (!e[0].is_string()) sc::fail(at + "/0", "expected a name");
      if (!e[1].is_null()) sc::number(e[1], at + "/1", -HUGE_VAL, HUGE_VAL);
      row.extras.emplace_back(e[0].get<std::string>(), json_number_or(e[1], nan));
    }
  } else {
    // A checkpoint of ftctune 0.1.0 (a service store from before the upgrade): the Bat
    // algorithm's two figures had fields of their own.
    for (const char* k : {"mean_loudness", "mean_pulse_rate"})
      if (j.contains(k) && j.at(k).is_number()) row.extras.emplace_back(k, j.at(k).get<double>());
  }
  return row;
}

}  // namespace

namespace state_check {

void fail(const std::string& path, const std::string& message) {
  throw InputError("checkpoint", path, message);
}

const json& member(const json& j, const std::string& path, const char* key) {
  if (!j.is_object()) fail(path, "expected an object, got " + json_io::json_type_name(j));
  const auto it = j.find(key);
  if (it == j.end()) fail(path + "/" + key, "is missing");
  return *it;
}

std::int64_t integer(const json& j, const std::string& path, std::int64_t lo, std::int64_t hi) {
  long long v = 0;
  const bool too_big = j.is_number_unsigned() &&
                       j.get<std::uint64_t>() > std::uint64_t{std::numeric_limits<long long>::max()};
  if (!j.is_number() || too_big || !json_io::json_to_int(j, v) || v < lo || v > hi)
    fail(path, "expected an integer in [" + std::to_string(lo) + ", " + std::to_string(hi) +
                   "], got " + j.dump());
  return v;
}

double number(const json& j, const std::string& path, double lo, double hi) {
  if (!j.is_number()) fail(path, "expected a number, got " + json_io::json_type_name(j));
  const double v = j.get<double>();
  if (!(v >= lo && v <= hi) || !std::isfinite(v))
    fail(path, "expected a number in [" + json_io::number_text(lo) + ", " +
                   json_io::number_text(hi) + "], got " + j.dump());
  return v;
}

double fitness(const json& j, const std::string& path) {
  if (j.is_null()) return std::numeric_limits<double>::infinity();
  // A run gives J >= 0, or -V/(1 + V) in [-1, 0) for an infeasible candidate (null: +inf). A
  // forged value below -1 is refused: fed to pagmo's replay as an infinite objective, it hung
  // bee_colony's onlooker loop.
  return number(j, path, -1.0, HUGE_VAL);
}

bool boolean(const json& j, const std::string& path) {
  if (!j.is_boolean()) fail(path, "expected true or false, got " + json_io::json_type_name(j));
  return j.get<bool>();
}

const json& array(const json& j, const std::string& path, std::size_t size) {
  if (!j.is_array()) fail(path, "expected an array, got " + json_io::json_type_name(j));
  if (j.size() != size)
    fail(path, "holds " + std::to_string(j.size()) + " elements, expected " +
                   std::to_string(size));
  return j;
}

Decision decision(const json& j, const std::string& path, const SearchSpace& space,
                  bool bounded) {
  array(j, path, space.dimension());
  Decision x(space.dimension());
  for (std::size_t k = 0; k < x.size(); ++k)
    x[k] = bounded ? number(j[k], path + "/" + std::to_string(k), space.lower[k], space.upper[k])
                   : number(j[k], path + "/" + std::to_string(k), -HUGE_VAL, HUGE_VAL);
  return x;
}

}  // namespace state_check

namespace {

// An algorithm's settings that also make optimisers of fronts: everything else is the wrapped
// settings' own, so that runs of one objective do not change by a bit.
class FrontSettings final : public AlgorithmSettings {
 public:
  FrontSettings(AlgorithmPtr inner, MakeFront make_front)
      : inner_(std::move(inner)), make_front_(std::move(make_front)) {}
  std::string type() const override { return inner_->type(); }
  json to_json() const override { return inner_->to_json(); }
  int population() const override { return inner_->population(); }
  int iterations() const override { return inner_->iterations(); }
  std::int64_t evaluations() const override { return inner_->evaluations(); }
  std::vector<std::string> history_columns() const override { return inner_->history_columns(); }
  std::vector<FieldError> validate(const std::string& path) const override {
    return inner_->validate(path);
  }
  std::unique_ptr<Optimizer> make(std::uint64_t seed, const SearchSpace& space) const override {
    return inner_->make(seed, space);
  }
  bool searches_front() const override { return true; }
  std::vector<FieldError> validate_front(std::size_t objectives,
                                         const std::string& path) const override {
    return inner_->validate_front(objectives, path);
  }
  std::unique_ptr<Optimizer> make_front(std::uint64_t seed, const SearchSpace& space,
                                        std::size_t objectives) const override {
    return make_front_(*inner_, seed, space, objectives);
  }
  AlgorithmPtr with_budget(std::int64_t budget) const override {
    AlgorithmPtr b = inner_->with_budget(budget);
    return b ? std::make_shared<FrontSettings>(std::move(b), make_front_) : nullptr;
  }

 private:
  AlgorithmPtr inner_;
  MakeFront make_front_;
};

}  // namespace

AlgorithmInfo with_front(AlgorithmInfo info, MakeFront make_front) {
  info.parse = [parse = info.parse, make_front](const json& j, const std::string& path,
                                                std::vector<FieldError>& errors) -> AlgorithmPtr {
    AlgorithmPtr a = parse(j, path, errors);
    return a ? std::make_shared<FrontSettings>(std::move(a), make_front) : nullptr;
  };
  return info;
}

std::vector<double> FunctionObjectives::operator()(const std::vector<Decision>& batch) {
  std::vector<double> J;
  J.reserve(batch.size());
  for (const ObjectiveVector& o : objective_vectors(batch)) {
    const double f = o.values.empty() ? 0.0 : o.values[0];
    const double fitness = !std::isfinite(f) || f < 0 ? 0.0
                           : f == 0                   ? std::numeric_limits<double>::infinity()
                                                      : 1.0 / f;  // as fitness_of (problem.hpp)
    J.push_back(constrained_fitness(fitness, o.violation));
  }
  return J;
}

AlgorithmPtr parse_algorithm(const json& j, const std::string& path,
                             std::vector<FieldError>& errors) {
  if (!j.is_object()) {
    errors.push_back({path, "expected an object, got " + json_io::json_type_name(j)});
    return nullptr;
  }
  std::string type = "bat";
  if (const auto it = j.find("type"); it != j.end()) {
    if (!it->is_string()) {
      errors.push_back({path + "/type", "expected a string, got " + json_io::json_type_name(*it)});
      return nullptr;
    }
    type = it->get<std::string>();
  }
  const AlgorithmInfo* info = find_algorithm(type);
  if (!info) {
    std::string known;
    for (const AlgorithmInfo& a : algorithms()) known += (known.empty() ? "" : ", ") + a.type;
    errors.push_back({path + "/type", "unknown algorithm \"" + type + "\" (known: " + known + ")"});
    return nullptr;
  }
  return info->parse(j, path, errors);
}

AlgorithmPtr make_algorithm(const json& settings) {
  std::vector<FieldError> errs;
  AlgorithmPtr a = parse_algorithm(settings, "", errs);
  throw_if_errors("algorithm", std::move(errs));
  return a;
}

const AlgorithmInfo* find_algorithm(std::string_view type) {
  for (const AlgorithmInfo& a : algorithms())
    if (a.type == type) return &a;
  return nullptr;
}

OptimizationResult run_optimizer(Optimizer& optimizer, BatchFitness& fitness,
                                 const IterationObserver& observer, const json* resume,
                                 const std::string& state_path) {
  bool go = true;
  if (resume) {
    try {
      optimizer.restore(*resume);
    } catch (const json::exception& e) {
      throw InputError("checkpoint", state_path,
                       std::string("damaged optimiser state: ") + e.what());
    } catch (const InputError& e) {
      std::vector<FieldError> errors = e.errors();
      for (FieldError& f : errors) f.path = state_path + f.path;
      throw InputError(e.source(), std::move(errors));
    }
  } else {
    fitness.begin_iteration(0);
    optimizer.initialize(fitness);
    go = !observer || observer(optimizer.history().back(), optimizer);
  }
  while (go && optimizer.iteration() < optimizer.iterations()) {
    fitness.begin_iteration(optimizer.iteration() + 1);
    optimizer.iterate(fitness);
    go = !observer || observer(optimizer.history().back(), optimizer);
  }
  return optimization_result(optimizer);
}

OptimizationResult optimization_result(const Optimizer& optimizer) {
  OptimizationResult r;
  const HistoryRow& last = optimizer.history().back();
  r.best = last.best;
  r.best_fitness = last.best_fitness;
  r.evaluations = last.evaluations;
  r.history = optimizer.history();
  r.completed = optimizer.iteration() == optimizer.iterations();
  return r;
}

std::vector<double> GenerationalOptimizer::evaluate(BatchFitness& fitness,
                                                    const std::vector<Decision>& batch) {
  std::vector<double> J = fitness(batch);
  if (J.size() != batch.size()) throw std::logic_error("fitness returned a wrong-sized batch");
  evaluations_ += static_cast<std::int64_t>(J.size());
  return J;
}

std::vector<double> GenerationalOptimizer::evaluate(BatchFitness& fitness,
                                                    const std::vector<Decision>& batch,
                                                    const std::vector<double>& caps) {
  std::vector<double> J = fitness.evaluate_capped(batch, caps);
  if (J.size() != batch.size()) throw std::logic_error("fitness returned a wrong-sized batch");
  evaluations_ += static_cast<std::int64_t>(J.size());
  return J;
}

std::vector<ObjectiveVector> GenerationalOptimizer::evaluate_objectives(
    BatchFitness& fitness, const std::vector<Decision>& batch) {
  return evaluate_objectives(fitness, batch, {});
}

std::vector<ObjectiveVector> GenerationalOptimizer::evaluate_objectives(
    BatchFitness& fitness, const std::vector<Decision>& batch, const std::vector<FrontCap>& caps) {
  std::vector<ObjectiveVector> F = caps.empty() ? fitness.objective_vectors(batch)
                                                : fitness.objective_vectors_capped(batch, caps);
  if (F.size() != batch.size())
    throw std::logic_error("objective vectors of a wrong-sized batch");
  for (const ObjectiveVector& f : F)
    if (f.values.size() != fitness.objectives())
      throw std::logic_error("an objective vector of the wrong size");
  evaluations_ += static_cast<std::int64_t>(F.size());
  return F;
}

void GenerationalOptimizer::record(std::vector<std::pair<std::string, double>> extras) {
  HistoryRow row;
  row.iteration = t_;
  row.best_fitness = best_fitness_;
  row.best = best_;
  row.evaluations = evaluations_;
  row.extras = std::move(extras);
  history_.push_back(std::move(row));
}

json GenerationalOptimizer::common_state(const char* algorithm) const {
  json history = json::array();
  for (const HistoryRow& h : history_) history.push_back(to_json(h));
  return {{"algorithm", algorithm}, {"t", t_},       {"evaluations", evaluations_},
          {"rng", rng_.save()},     {"best", best_}, {"best_fitness", json_number(best_fitness_)},
          {"history", history}};
}

void GenerationalOptimizer::restore_common(const json& s, const char* algorithm,
                                           std::int64_t per_generation,
                                           std::int64_t max_evaluations, bool bounded) {
  namespace sc = state_check;
  if (!s.is_object() || s.value("algorithm", "") != algorithm)
    throw InputError("checkpoint", "",
                     std::string("not a state of the ") + algorithm + " optimiser");
  // Iteration t of this run's T, and the evaluations that t iterations made: per_generation
  // each (the initial population included), or for an optimiser whose generations differ (or
  // that stops on its own), at most the run's budget.
  const auto t = static_cast<int>(sc::integer(sc::member(s, "", "t"), "/t", 0, iterations_));
  const auto expected = [&](int i) {
    return per_generation > 0 ? per_generation * (i + 1) : std::int64_t{-1};
  };
  const std::int64_t evaluations =
      expected(t) >= 0 ? sc::integer(sc::member(s, "", "evaluations"), "/evaluations", expected(t),
                                     expected(t))
                       : sc::integer(sc::member(s, "", "evaluations"), "/evaluations", 0,
                                     max_evaluations);
  const json& rng = sc::member(s, "", "rng");
  Rng engine(0);
  if (!rng.is_string() || !engine.load(rng.get<std::string>()))
    sc::fail("/rng", "is not the state of the random engine (std::mt19937_64's text)");
  Decision best = sc::decision(sc::member(s, "", "best"), "/best", space_, bounded);
  const double best_fitness = sc::fitness(sc::member(s, "", "best_fitness"), "/best_fitness");
  // One row per iteration 0..t, each with the evaluations of its iteration, the last with the
  // state's own best point.
  const json& history =
      sc::array(sc::member(s, "", "history"), "/history", static_cast<std::size_t>(t) + 1);
  std::vector<HistoryRow> rows;
  rows.reserve(history.size());
  std::int64_t previous = 0;
  for (int i = 0; i <= t; ++i) {
    const std::int64_t lo = expected(i) >= 0 ? expected(i) : previous;
    const std::int64_t hi = expected(i) >= 0 ? expected(i) : evaluations;
    rows.push_back(history_row_from_json(history[static_cast<std::size_t>(i)],
                                         "/history/" + std::to_string(i), i, lo, hi, space_,
                                         bounded));
    previous = rows.back().evaluations;
  }
  const HistoryRow& last = rows.back();
  const std::string at = "/history/" + std::to_string(t);
  if (last.evaluations != evaluations)
    sc::fail(at + "/evaluations", "is not the state's evaluations (" +
                                      std::to_string(evaluations) + ")");
  if (last.best != best || !(last.best_fitness == best_fitness))
    sc::fail(at + "/best", "is not the state's best point");
  t_ = t;
  rng_ = engine;
  evaluations_ = evaluations;
  best_ = std::move(best);
  best_fitness_ = best_fitness;
  history_ = std::move(rows);
}

}  // namespace ftc::tune
