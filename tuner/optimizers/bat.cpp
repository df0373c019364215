#include "ftc/tune/optimizers/bat.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <limits>

#include "ftc/runtime/json_reader.hpp"
#include "ftc/sim/elementary.hpp"
#include "ftc/tune/optimizers/state_check.hpp"

namespace ftc::tune {

using json_io::json_number;

namespace {

std::shared_ptr<const schema::Object<BatSettings>> bat_shape() {
  using S = BatSettings;
  using schema::IntRange;
  using schema::Range;
  static const auto shape = std::make_shared<const schema::Object<S>>(
      schema::Object<S>("The Bat algorithm (paper §5): M bats, T iterations, M·(T+1) evaluations")
          .integer("population", &S::population, IntRange{1, 100000}, "number of bats M")
          .integer("iterations", &S::iterations, IntRange{0, 100000},
                   "iterations T after the initial population")
          .number("f_min", &S::f_min, Range::non_negative(), "lowest pulse frequency")
          .number("f_max", &S::f_max, Range::any(), "highest pulse frequency (>= f_min)")
          .number("loudness", &S::loudness, Range::half_open_unit(), "initial loudness A0")
          .number("pulse_rate", &S::pulse_rate, Range::unit(), "initial pulse rate r0")
          .number("loudness_decay", &S::loudness_decay, Range::open_unit(),
                  "factor α on the loudness after an accepted move")
          .number("pulse_rate_growth", &S::pulse_rate_growth, Range::positive(),
                  "γ of r = r0 (1 - exp(-γ t))")
          .rule([](const S& s, const std::string& path, schema::Errors& e) {
            if (std::isfinite(s.f_min) && s.f_min >= 0 && std::isfinite(s.f_max) &&
                s.f_max < s.f_min)
              e.push_back({path + "/f_max", "must be >= f_min " + json_io::number_text(s.f_min) +
                                                " (got " + json_io::number_text(s.f_max) + ")"});
          }));
  return shape;
}

}  // namespace

std::vector<FieldError> BatSettings::validate(const std::string& path) const {
  std::vector<FieldError> errs;
  bat_shape()->validate(*this, path, errs);
  return errs;
}

AlgorithmInfo bat_algorithm_info() {
  return struct_algorithm<BatSettings>(
      "bat", "the Bat algorithm of the paper (§5, Appendix A)", bat_shape(),
      [](const BatSettings& s, std::uint64_t seed, const SearchSpace& space) {
        return std::make_unique<BatAlgorithm>(s, seed, space);
      },
      {"mean_loudness", "mean_pulse_rate"});
}

Decision bat_frequency_move(const SearchSpace& space, const Decision& x, Decision& v,
                            const Decision& best, double f) {
  Decision c(x.size());
  for (std::size_t j = 0; j < x.size(); ++j) {
    v[j] += (best[j] - x[j]) * f;
    c[j] = space.clamp(j, x[j] + v[j]);
  }
  return c;
}

BatAlgorithm::BatAlgorithm(const BatSettings& settings, std::uint64_t seed,
                           const SearchSpace& space)
    : GenerationalOptimizer(settings.iterations, seed, space), settings_(settings) {
  assert(settings.validate("").empty());
  assert(space.dimension() > 0);
}

void BatAlgorithm::initialize(BatchFitness& fitness) {
  const std::size_t d = space_.dimension();
  bats_.assign(static_cast<std::size_t>(settings_.population), Bat{});
  std::vector<Decision> batch;
  for (Bat& b : bats_) {
    b.x.resize(d);
    b.v.resize(d);
    for (std::size_t j = 0; j < d; ++j) b.x[j] = rng_.uniform(space_.lower[j], space_.upper[j]);
    for (std::size_t j = 0; j < d; ++j) b.v[j] = rng_.uniform();
    b.loudness = settings_.loudness;
    b.pulse_rate = settings_.pulse_rate;
    batch.push_back(b.x);
  }
  const std::vector<double> J = evaluate(fitness, batch);
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

void BatAlgorithm::iterate(BatchFitness& fitness) {
  assert(t_ >= 0 && "initialize() first");
  const int t = t_ + 1;
  const std::size_t d = space_.dimension();
  const BatSettings& c = settings_;

  double mean_loudness = 0.0;
  for (const Bat& b : bats_) mean_loudness += b.loudness;
  mean_loudness /= static_cast<double>(bats_.size());

  const Decision best = best_;  // x* as it was at the start of the iteration
  std::vector<Decision> candidates;
  candidates.reserve(bats_.size());
  for (Bat& b : bats_) {
    const double f = c.f_min + (c.f_max - c.f_min) * rng_.uniform();
    Decision cand = bat_frequency_move(space_, b.x, b.v, best, f);
    if (rng_.uniform() > b.pulse_rate) {  // local random walk around the best (eq. 39)
      for (std::size_t j = 0; j < d; ++j)
        cand[j] = space_.clamp(j, best[j] + rng_.uniform(-1.0, 1.0) * mean_loudness);
    }
    candidates.push_back(std::move(cand));
  }

  // The loudness tests come next in the stream whatever the fitness: drawn here, before the
  // evaluation, they are the same numbers, and they tell each candidate's cap (issue 27). A
  // candidate whose loudness test fails can only change x*, so it matters only above J(x*); one
  // whose test passes also moves its bat when J >= J_i (and J_i <= J(x*)). Below its cap a
  // candidate changes nothing: x* only moves for J > J(x*) at the start of the iteration or
  // later, which is at least the cap.
  std::vector<double> loudness_test(bats_.size()), caps(bats_.size());
  for (std::size_t i = 0; i < bats_.size(); ++i) {
    loudness_test[i] = rng_.uniform();
    caps[i] = loudness_test[i] < bats_[i].loudness ? std::min(bats_[i].fitness, best_fitness_)
                                                   : best_fitness_;
  }

  const std::vector<double> J = evaluate(fitness, candidates, caps);

  // ftctune's exp, not libm's, so that the schedule is the same bits on every CPU.
  const double pulse = c.pulse_rate * (1.0 - sim::math::exp(-c.pulse_rate_growth * t));
  for (std::size_t i = 0; i < bats_.size(); ++i) {
    Bat& b = bats_[i];
    if (loudness_test[i] < b.loudness && J[i] >= b.fitness) {
      b.x = candidates[i];
      b.fitness = J[i];
      b.loudness *= c.loudness_decay;
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
  namespace sc = state_check;
  restore_common(s, "bat", settings_.population, 0, true);
  // Every bat: a position inside the space (every move is clamped to it), a finite velocity,
  // a loudness that only decays from A0 and a pulse rate below r0.
  const nlohmann::json& bats =
      sc::array(sc::member(s, "", "bats"), "/bats", static_cast<std::size_t>(settings_.population));
  std::vector<Bat> restored;
  restored.reserve(bats.size());
  for (std::size_t i = 0; i < bats.size(); ++i) {
    const std::string at = "/bats/" + std::to_string(i);
    const nlohmann::json& b = bats[i];
    Bat bat;
    bat.x = sc::decision(sc::member(b, at, "x"), at + "/x", space_, true);
    bat.v = sc::decision(sc::member(b, at, "v"), at + "/v", space_, false);
    bat.loudness = sc::number(sc::member(b, at, "loudness"), at + "/loudness", 0.0,
                              settings_.loudness);
    bat.pulse_rate = sc::number(sc::member(b, at, "pulse_rate"), at + "/pulse_rate", 0.0,
                                settings_.pulse_rate);
    bat.fitness = sc::fitness(sc::member(b, at, "fitness"), at + "/fitness");
    restored.push_back(std::move(bat));
  }
  bats_ = std::move(restored);
}

void BatAlgorithm::record_iteration() {
  double loudness = 0.0, pulse_rate = 0.0;
  for (const Bat& b : bats_) {
    loudness += b.loudness;
    pulse_rate += b.pulse_rate;
  }
  const double n = static_cast<double>(bats_.size());
  record({{"mean_loudness", loudness / n}, {"mean_pulse_rate", pulse_rate / n}});
}

}  // namespace ftc::tune
