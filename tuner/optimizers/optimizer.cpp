#include "ftc/tune/optimizers/optimizer.hpp"

#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include "ftc/runtime/json_reader.hpp"

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

HistoryRow history_row_from_json(const json& j) {
  constexpr double nan = std::numeric_limits<double>::quiet_NaN();
  HistoryRow row;
  row.iteration = j.at("iteration").get<int>();
  row.best_fitness = json_number_or(j.at("best_fitness"), std::numeric_limits<double>::infinity());
  row.best = j.at("best").get<std::vector<double>>();
  row.evaluations = j.at("evaluations").get<std::int64_t>();
  if (j.contains("extras")) {
    for (const json& e : j.at("extras"))
      row.extras.emplace_back(e.at(0).get<std::string>(), json_number_or(e.at(1), nan));
  } else {
    // A checkpoint of ftctune 0.1.0 (a service store from before the upgrade): the Bat
    // algorithm's two figures had fields of their own.
    for (const char* k : {"mean_loudness", "mean_pulse_rate"})
      if (j.contains(k) && j.at(k).is_number()) row.extras.emplace_back(k, j.at(k).get<double>());
  }
  return row;
}

}  // namespace

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
                                 const IterationObserver& observer, const json* resume) {
  OptimizationResult r;
  bool go = true;
  if (resume) {
    try {
      optimizer.restore(*resume);
    } catch (const json::exception& e) {
      throw InputError("checkpoint", "", std::string("damaged optimiser state: ") + e.what());
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

void GenerationalOptimizer::restore_common(const json& s, const char* algorithm) {
  if (!s.is_object() || s.value("algorithm", "") != algorithm)
    throw InputError("checkpoint", "",
                     std::string("not a state of the ") + algorithm + " optimiser");
  t_ = s.at("t").get<int>();
  evaluations_ = s.at("evaluations").get<std::int64_t>();
  rng_.load(s.at("rng").get<std::string>());
  best_ = s.at("best").get<Decision>();
  best_fitness_ = json_number_or(s.at("best_fitness"), std::numeric_limits<double>::infinity());
  history_.clear();
  for (const json& h : s.at("history")) history_.push_back(history_row_from_json(h));
}

}  // namespace ftc::tune
