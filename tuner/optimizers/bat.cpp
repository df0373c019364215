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

void BatMotion::start(const BatSettings& s, const SearchSpace& space, Rng& rng) {
  const std::size_t d = space.dimension();
  x.resize(d);
  v.resize(d);
  for (std::size_t j = 0; j < d; ++j) x[j] = rng.uniform(space.lower[j], space.upper[j]);
  for (std::size_t j = 0; j < d; ++j) v[j] = rng.uniform();
  loudness = s.loudness;
  pulse_rate = s.pulse_rate;
}

Decision BatMotion::candidate(const BatSettings& s, const SearchSpace& space, Rng& rng,
                              const Decision& leader, double mean_loudness) {
  const double f = s.f_min + (s.f_max - s.f_min) * rng.uniform();
  Decision c = bat_frequency_move(space, x, v, leader, f);
  if (rng.uniform() > pulse_rate) {  // local random walk around the leader (eq. 39)
    for (std::size_t j = 0; j < space.dimension(); ++j)
      c[j] = space.clamp(j, leader[j] + rng.uniform(-1.0, 1.0) * mean_loudness);
  }
  return c;
}

void BatMotion::accept(const Decision& c, const BatSettings& s, double pulse) {
  x = c;
  loudness *= s.loudness_decay;
  pulse_rate = pulse;
}

nlohmann::json BatMotion::to_json() const {
  return {{"x", x}, {"v", v}, {"loudness", loudness}, {"pulse_rate", pulse_rate}};
}

BatMotion BatMotion::from_json(const nlohmann::json& b, const std::string& at,
                               const BatSettings& s, const SearchSpace& space) {
  namespace sc = state_check;
  BatMotion m;
  m.x = sc::decision(sc::member(b, at, "x"), at + "/x", space, true);
  m.v = sc::decision(sc::member(b, at, "v"), at + "/v", space, false);
  m.loudness = sc::number(sc::member(b, at, "loudness"), at + "/loudness", 0.0, s.loudness);
  m.pulse_rate =
      sc::number(sc::member(b, at, "pulse_rate"), at + "/pulse_rate", 0.0, s.pulse_rate);
  return m;
}

double bat_pulse_rate(const BatSettings& s, int t) {
  return s.pulse_rate * (1.0 - sim::math::exp(-s.pulse_rate_growth * t));
}

BatAlgorithm::BatAlgorithm(const BatSettings& settings, std::uint64_t seed,
                           const SearchSpace& space)
    : GenerationalOptimizer(settings.iterations, seed, space), settings_(settings) {
  assert(settings.validate("").empty());
  assert(space.dimension() > 0);
}

void BatAlgorithm::initialize(BatchFitness& fitness) {
  bats_.assign(static_cast<std::size_t>(settings_.population), Bat{});
  std::vector<Decision> batch;
  for (Bat& b : bats_) {
    b.start(settings_, space_, rng_);
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
  const double mean_loudness = bat_means(bats_).first;
  const Decision best = best_;  // x* as it was at the start of the iteration
  std::vector<Decision> candidates;
  candidates.reserve(bats_.size());
  for (Bat& b : bats_)
    candidates.push_back(b.candidate(settings_, space_, rng_, best, mean_loudness));

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

  const double pulse = bat_pulse_rate(settings_, t);
  for (std::size_t i = 0; i < bats_.size(); ++i) {
    Bat& b = bats_[i];
    if (loudness_test[i] < b.loudness && J[i] >= b.fitness) {
      b.accept(candidates[i], settings_, pulse);
      b.fitness = J[i];
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
  for (const Bat& b : bats_) {
    nlohmann::json j = b.to_json();
    j["fitness"] = json_number(b.fitness);
    s["bats"].push_back(std::move(j));
  }
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
    static_cast<BatMotion&>(bat) = BatMotion::from_json(b, at, settings_, space_);
    bat.fitness = sc::fitness(sc::member(b, at, "fitness"), at + "/fitness");
    restored.push_back(std::move(bat));
  }
  bats_ = std::move(restored);
}

void BatAlgorithm::record_iteration() {
  const auto [loudness, pulse_rate] = bat_means(bats_);
  record({{"mean_loudness", loudness}, {"mean_pulse_rate", pulse_rate}});
}

}  // namespace ftc::tune
