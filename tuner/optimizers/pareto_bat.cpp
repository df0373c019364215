#include "ftc/tune/optimizers/pareto_bat.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <limits>
#include <numeric>

#include "ftc/runtime/json_reader.hpp"
#include "ftc/sim/elementary.hpp"
#include "ftc/tune/optimizers/state_check.hpp"

namespace ftc::tune {

using json_io::json_number;
using nlohmann::json;

namespace pareto {

namespace {
constexpr double inf = std::numeric_limits<double>::infinity();
double value(double v) { return std::isnan(v) ? inf : v; }
}  // namespace

double log_value(double v) {
  if (!(v < inf)) return inf;  // +inf and NaN
  // ftctune's log, not libm's, so that the same bits come out on every CPU.
  return sim::math::log(std::max(v, kLogFloor)) * 0.43429448190325182765;  // 1/ln 10
}

bool dominates(const ObjectiveVector& a, const ObjectiveVector& b) {
  const bool fa = a.feasible(), fb = b.feasible();
  if (fa != fb) return fa;
  if (!fa) return a.violation < b.violation;
  bool better = false;
  for (std::size_t k = 0; k < a.values.size() && k < b.values.size(); ++k) {
    const double x = value(a.values[k]), y = value(b.values[k]);
    if (x > y) return false;
    better = better || x < y;
  }
  return better;
}

std::vector<std::vector<std::size_t>> nondominated_sort(const std::vector<ObjectiveVector>& p) {
  const std::size_t n = p.size();
  std::vector<std::vector<std::size_t>> dominated(n);  // S_i: the points i dominates
  std::vector<std::size_t> count(n, 0);                // n_i: how many dominate i
  std::vector<std::vector<std::size_t>> fronts(1);
  for (std::size_t i = 0; i < n; ++i) {
    for (std::size_t j = 0; j < n; ++j) {
      if (i == j) continue;
      if (dominates(p[i], p[j]))
        dominated[i].push_back(j);
      else if (dominates(p[j], p[i]))
        ++count[i];
    }
    if (count[i] == 0) fronts[0].push_back(i);
  }
  while (!fronts.back().empty()) {
    std::vector<std::size_t> next;
    for (std::size_t i : fronts.back())
      for (std::size_t j : dominated[i])
        if (--count[j] == 0) next.push_back(j);
    std::sort(next.begin(), next.end());
    fronts.push_back(std::move(next));
  }
  fronts.pop_back();
  return fronts;
}

std::vector<double> crowding_distance(const std::vector<ObjectiveVector>& p,
                                      const std::vector<std::size_t>& front) {
  const std::size_t n = front.size();
  std::vector<double> d(n, 0.0);
  if (n == 0) return d;
  const std::size_t m = p[front[0]].values.size();
  std::vector<std::size_t> order(n);
  for (std::size_t k = 0; k < m; ++k) {
    const auto at = [&](std::size_t i) { return log_value(p[front[i]].values[k]); };
    std::iota(order.begin(), order.end(), std::size_t{0});
    std::stable_sort(order.begin(), order.end(),
                     [&](std::size_t a, std::size_t b) { return at(a) < at(b); });
    d[order.front()] = inf;
    d[order.back()] = inf;
    const double range = at(order.back()) - at(order.front());
    if (!(range > 0) || !std::isfinite(range)) continue;
    for (std::size_t i = 1; i + 1 < n; ++i)
      d[order[i]] += (at(order[i + 1]) - at(order[i - 1])) / range;
  }
  return d;
}

}  // namespace pareto

bool FrontCap::stops(const ObjectiveVector& lower) const {
  if (may_move && !pareto::dominates(bat, lower)) return false;
  if (!lower.feasible()) return true;
  return archive && std::any_of(archive->begin(), archive->end(), [&](const ObjectiveVector& a) {
           return pareto::dominates(a, lower);
         });
}

namespace {

// The scalar fitness of a point, for the history: as constrained_fitness(fitness_of(f1), V).
double scalar_fitness(const ObjectiveVector& f) {
  const double v = f.values.empty() ? 0.0 : f.values[0];
  const double J = !std::isfinite(v) || v < 0 ? 0.0
                   : v == 0                   ? std::numeric_limits<double>::infinity()
                                              : 1.0 / v;
  return constrained_fitness(J, f.violation);
}

bool finite_values(const ObjectiveVector& f) {
  return std::all_of(f.values.begin(), f.values.end(), [](double v) { return std::isfinite(v); });
}

json to_json(const ObjectiveVector& f) {
  json values = json::array();
  for (double v : f.values) values.push_back(json_number(v));
  return {{"values", values}, {"violation", json_number(f.violation)}};
}

ObjectiveVector objectives_from_json(const json& j, const std::string& path, std::size_t n) {
  namespace sc = state_check;
  ObjectiveVector f;
  const json& values = sc::array(sc::member(j, path, "values"), path + "/values", n);
  for (std::size_t k = 0; k < n; ++k)
    f.values.push_back(sc::fitness(values[k], path + "/values/" + std::to_string(k)));
  f.violation = sc::fitness(sc::member(j, path, "violation"), path + "/violation");
  if (!(f.violation >= 0)) sc::fail(path + "/violation", "expected a violation >= 0");
  return f;
}

}  // namespace

ParetoBatAlgorithm::ParetoBatAlgorithm(const BatSettings& settings, std::uint64_t seed,
                                       const SearchSpace& space, std::size_t objectives)
    : GenerationalOptimizer(settings.iterations, seed, space),
      settings_(settings),
      objectives_(objectives),
      capacity_(std::max<std::size_t>(100, static_cast<std::size_t>(settings.population))) {
  assert(settings.validate("").empty());
  assert(space.dimension() > 0 && objectives >= 2);
}

void ParetoBatAlgorithm::initialize(BatchFitness& fitness) {
  bats_.assign(static_cast<std::size_t>(settings_.population), Bat{});
  archive_.clear();
  std::vector<Decision> batch;
  for (Bat& b : bats_) {  // the draws of bat.hpp's initialisation, in its order
    b.start(settings_, space_, rng_);
    batch.push_back(b.x);
  }
  const std::vector<ObjectiveVector> F = evaluate_objectives(fitness, batch);
  for (std::size_t i = 0; i < bats_.size(); ++i) {
    bats_[i].f = F[i];
    offer(bats_[i].x, F[i]);
  }
  t_ = 0;
  record_iteration();
}

void ParetoBatAlgorithm::iterate(BatchFitness& fitness) {
  assert(t_ >= 0 && "initialize() first");
  const int t = t_ + 1;
  const double mean_loudness = bat_means(bats_).first;

  // The leader pool as it is at the start of the iteration, with its crowding distances.
  std::vector<const Decision*> pool;
  std::vector<ObjectiveVector> pool_f;
  if (!archive_.empty()) {
    for (const Member& m : archive_) {
      pool.push_back(&m.x);
      pool_f.push_back(m.f);
    }
  } else {
    std::vector<ObjectiveVector> all;
    for (const Bat& b : bats_) all.push_back(b.f);
    const std::vector<std::vector<std::size_t>> fronts = pareto::nondominated_sort(all);
    for (std::size_t i : fronts.front()) {
      pool.push_back(&bats_[i].x);
      pool_f.push_back(bats_[i].f);
    }
  }
  std::vector<std::size_t> every(pool.size());
  std::iota(every.begin(), every.end(), std::size_t{0});
  const std::vector<double> crowding = pareto::crowding_distance(pool_f, every);
  const auto draw = [&] {
    const auto k = static_cast<std::size_t>(rng_.uniform() * static_cast<double>(pool.size()));
    return std::min(k, pool.size() - 1);
  };

  std::vector<Decision> candidates;
  candidates.reserve(bats_.size());
  for (Bat& b : bats_) {
    const std::size_t k1 = draw(), k2 = draw();
    const Decision leader = *pool[crowding[k2] > crowding[k1] ? k2 : k1];
    candidates.push_back(b.candidate(settings_, space_, rng_, leader, mean_loudness));
  }

  // The loudness tests are drawn before the evaluation (the same draws in the same order as
  // after it: nothing draws in between), so that the fitness may stop a candidate whose value
  // can change no decision (FrontCap). The archive it is given is this one: while it cannot
  // overflow during the offers below, a point of it that leaves is dominated by one that stays.
  std::vector<double> loud(bats_.size());
  for (double& u : loud) u = rng_.uniform();
  std::shared_ptr<const std::vector<ObjectiveVector>> archive;
  if (archive_.size() + bats_.size() <= capacity_) {
    auto points = std::make_shared<std::vector<ObjectiveVector>>();
    for (const Member& m : archive_) points->push_back(m.f);
    archive = std::move(points);
  }
  std::vector<FrontCap> caps(bats_.size());
  for (std::size_t i = 0; i < bats_.size(); ++i)
    caps[i] = {loud[i] < bats_[i].loudness, bats_[i].f, archive};
  const std::vector<ObjectiveVector> F = evaluate_objectives(fitness, candidates, caps);

  const double pulse = bat_pulse_rate(settings_, t);
  for (std::size_t i = 0; i < bats_.size(); ++i) {
    Bat& b = bats_[i];
    if (loud[i] < b.loudness && !pareto::dominates(b.f, F[i])) {
      b.accept(candidates[i], settings_, pulse);
      b.f = F[i];
    }
    offer(candidates[i], F[i]);
  }
  t_ = t;
  record_iteration();
}

void ParetoBatAlgorithm::offer(const Decision& x, const ObjectiveVector& f) {
  if (!f.feasible() || !finite_values(f)) return;
  for (const Member& m : archive_)
    if (m.f.values == f.values || pareto::dominates(m.f, f)) return;
  std::erase_if(archive_, [&](const Member& m) { return pareto::dominates(f, m.f); });
  archive_.push_back({x, f});
  if (archive_.size() <= capacity_) return;
  std::vector<ObjectiveVector> F;
  for (const Member& m : archive_) F.push_back(m.f);
  std::vector<std::size_t> every(F.size());
  std::iota(every.begin(), every.end(), std::size_t{0});
  const std::vector<double> crowding = pareto::crowding_distance(F, every);
  const auto least = std::min_element(crowding.begin(), crowding.end()) - crowding.begin();
  archive_.erase(archive_.begin() + least);
}

void ParetoBatAlgorithm::record_iteration() {
  if (!archive_.empty()) {
    std::size_t best = 0;
    for (std::size_t i = 1; i < archive_.size(); ++i)
      if (archive_[i].f.values[0] < archive_[best].f.values[0]) best = i;
    best_ = archive_[best].x;
    best_fitness_ = scalar_fitness(archive_[best].f);
  } else {
    std::size_t best = 0;
    for (std::size_t i = 1; i < bats_.size(); ++i) {
      const ObjectiveVector &a = bats_[i].f, &b = bats_[best].f;
      if (a.violation < b.violation ||
          (a.violation == b.violation && pareto::log_value(a.values[0]) <
                                             pareto::log_value(b.values[0])))
        best = i;
    }
    best_ = bats_[best].x;
    best_fitness_ = scalar_fitness(bats_[best].f);
  }
  const auto [loudness, pulse_rate] = bat_means(bats_);
  record({{"mean_loudness", loudness}, {"mean_pulse_rate", pulse_rate}});
}

json ParetoBatAlgorithm::state() const {
  json s = common_state("pareto_bat");
  s["objectives"] = objectives_;
  s["bats"] = json::array();
  for (const Bat& b : bats_) {
    json j = b.to_json();
    j["f"] = to_json(b.f);
    s["bats"].push_back(std::move(j));
  }
  s["archive"] = json::array();
  for (const Member& m : archive_) s["archive"].push_back({{"x", m.x}, {"f", to_json(m.f)}});
  return s;
}

void ParetoBatAlgorithm::restore(const json& s) {
  namespace sc = state_check;
  // Checked before the common part changes anything, like the rest below.
  const auto n = static_cast<std::size_t>(
      sc::integer(sc::member(s, "", "objectives"), "/objectives", static_cast<std::int64_t>(objectives_),
                  static_cast<std::int64_t>(objectives_)));
  const json& bats =
      sc::array(sc::member(s, "", "bats"), "/bats", static_cast<std::size_t>(settings_.population));
  std::vector<Bat> restored;
  restored.reserve(bats.size());
  for (std::size_t i = 0; i < bats.size(); ++i) {
    const std::string at = "/bats/" + std::to_string(i);
    const json& b = bats[i];
    Bat bat;
    static_cast<BatMotion&>(bat) = BatMotion::from_json(b, at, settings_, space_);
    bat.f = objectives_from_json(sc::member(b, at, "f"), at + "/f", n);
    restored.push_back(std::move(bat));
  }
  // The archive: at most its capacity of feasible points with finite goals, none dominating or
  // equal to another.
  const json& archive = sc::member(s, "", "archive");
  if (!archive.is_array() || archive.size() > capacity_)
    sc::fail("/archive", "expected an array of at most " + std::to_string(capacity_) + " points");
  std::vector<Member> members;
  for (std::size_t i = 0; i < archive.size(); ++i) {
    const std::string at = "/archive/" + std::to_string(i);
    Member m;
    m.x = sc::decision(sc::member(archive[i], at, "x"), at + "/x", space_, true);
    m.f = objectives_from_json(sc::member(archive[i], at, "f"), at + "/f", n);
    if (!m.f.feasible() || !finite_values(m.f))
      sc::fail(at + "/f", "an archive point is feasible with finite goals");
    for (std::size_t k = 0; k < members.size(); ++k)
      if (members[k].f.values == m.f.values || pareto::dominates(members[k].f, m.f) ||
          pareto::dominates(m.f, members[k].f))
        sc::fail(at + "/f", "is not mutually non-dominated with /archive/" + std::to_string(k));
    members.push_back(std::move(m));
  }
  restore_common(s, "pareto_bat", settings_.population, 0, true);
  bats_ = std::move(restored);
  archive_ = std::move(members);
}

AlgorithmInfo pareto_bat_info() {
  return with_front(bat_algorithm_info(),
                    [](const AlgorithmSettings& a, std::uint64_t seed, const SearchSpace& space,
                       std::size_t objectives) -> std::unique_ptr<Optimizer> {
                      const auto& s = dynamic_cast<const StructSettings<BatSettings>&>(a);
                      return std::make_unique<ParetoBatAlgorithm>(s.settings(), seed, space,
                                                                  objectives);
                    });
}

}  // namespace ftc::tune
