#include "ftc/tune/job/ensemble.hpp"

#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>

#include "ftc/runtime/json_reader.hpp"
#include "ftc/runtime/schema.hpp"
#include "ftc/sim/elementary.hpp"
#include "ftc/sim/plant_plugin.hpp"
#include "ftc/sim/plants.hpp"
#include "job/shapes.hpp"

namespace ftc::tune {

using nlohmann::json;
using schema::Errors;

// --- the distributions --------------------------------------------------------------------------

double Distribution::draw(double u) const {
  switch (kind) {
    case Kind::constant:
      return a;
    case Kind::uniform:
      return a + (b - a) * u;
    case Kind::log_uniform:
      // ftctune's own exp and log, not libm's: the members are the same on every CPU.
      return sim::math::exp(sim::math::log(a) + (sim::math::log(b) - sim::math::log(a)) * u);
  }
  return a;
}

std::size_t Choice::pick(double u) const {
  double total = 0.0;
  for (double w : weights) total += w;
  const double target = u * total;
  double cumulative = 0.0;
  std::size_t last = 0;
  for (std::size_t i = 0; i < weights.size(); ++i) {
    if (weights[i] <= 0.0) continue;
    cumulative += weights[i];
    last = i;
    if (cumulative > target) return i;
  }
  return last;  // rounding at u just below 1
}

// --- expansion ---------------------------------------------------------------------------------

std::int64_t ensemble_count(const Job& job, std::optional<std::int64_t> count) {
  if (count && (*count < 1 || *count > kMaxEnsembleCount))
    throw InputError("--count", "",
                     "must be between 1 and " + std::to_string(kMaxEnsembleCount) + ", got " +
                         std::to_string(*count));
  const std::int64_t n = count.value_or(job.ensemble->count);
  throw_if_errors("--count " + std::to_string(n), member_name_errors(job, n));
  return n;
}

const sim::Scenario* find_ensemble_base(const Job& job) {
  const std::string& base = job.ensemble->base;
  if (base.empty()) return job.scenarios.empty() ? nullptr : &job.scenarios.front();
  for (const sim::Scenario& s : job.scenarios)
    if (s.name == base) return &s;
  return nullptr;
}

const sim::Scenario& ensemble_base(const Job& job) {
  if (const sim::Scenario* base = find_ensemble_base(job)) return *base;
  throw InputError("job " + job.name, "/ensemble/base",
                   "no scenario is named \"" + job.ensemble->base + "\"");
}

sim::Scenario scaled_base(const Job& job, const ParameterFactors& parameter_factors,
                          const std::vector<double>& state_factor, double disturbance_factor) {
  const sim::Scenario& base = ensemble_base(job);
  const sim::PlantKind& kind = *sim::find_plant_kind(job.plant.model);
  sim::Scenario s = base;
  // Every uncertain parameter's true values, the base's or the plant's, by its factors.
  for (const sim::UncertainParameter& u : kind.uncertain) {
    if (u.per_actuator) continue;  // the base's, if it has them (apply_actuator_draws)
    const std::vector<double>* given = base.true_value(u.parameter);
    std::vector<double> values =
        given ? *given : kind.parameter_values(job.plant.values, u.parameter);
    for (const auto& [parameter, factors] : parameter_factors)
      if (parameter == u.parameter) sim::PlantKind::scale(u, values, factors);
    s.set_true_value(u.parameter, std::move(values));
  }
  for (std::size_t i = 0; i < s.initial_state.size() && i < state_factor.size(); ++i)
    s.initial_state[i] *= state_factor[i];
  for (sim::DisturbanceTerm& t : s.disturbance) t.amplitude *= disturbance_factor;
  return s;
}

void apply_actuator_draws(const Job& job, sim::Scenario& s, const std::vector<double>& scale_draws,
                          const std::vector<double>& misalignment_draws) {
  const EnsembleConfig& e = *job.ensemble;
  const sim::PlantKind& kind = *sim::find_plant_kind(job.plant.model);
  const auto m = static_cast<std::size_t>(kind.actuators_of(job.plant.values));
  // A scale multiplies the base's effectiveness (the model's: 1); an angle adds to its
  // misalignment (the model's: 0).
  enum class Combine { multiply, add };
  for (const auto& [parameter, d, draws, model_value, combine] :
       {std::tuple{"actuator_scale", &e.actuator_scale, &scale_draws, 1.0, Combine::multiply},
        std::tuple{"actuator_misalignment", &e.actuator_misalignment, &misalignment_draws, 0.0,
                   Combine::add}}) {
    if (!*d || !kind.find_uncertain(parameter)) continue;
    const std::vector<double>* given = s.true_value(parameter);
    std::vector<double> v = given && given->size() == m ? *given
                                                         : std::vector<double>(m, model_value);
    for (std::size_t j = 0; j < m && j < draws->size(); ++j)
      v[j] = combine == Combine::multiply ? v[j] * (*draws)[j] : v[j] + (*draws)[j];
    s.set_true_value(parameter, std::move(v));
  }
}

// A whole number in [lo, hi] from a uniform draw u in [0, 1): lo + floor(u (hi − lo + 1)),
// hi at most (the faults' count and the sensors' delay).
static int uniform_int(double u, int lo, int hi) {
  return std::min(hi, lo + static_cast<int>(std::floor(u * (hi - lo + 1))));
}

// SPEC §18's sensor draws of a member, in SensorDistribution's order.
void draw_sensors(const SensorDistribution& d, int axes, SplitMix64& r, sim::Scenario& s) {
  sim::SensorModel m = s.sensors.value_or(sim::SensorModel{});
  const auto draw = [&](const std::optional<Distribution>& dist, double& value) {
    const double u = r.uniform();  // consumed whether or not the entry is given
    if (dist) value = dist->draw(u);
  };
  draw(d.angle_noise, m.angle.noise);
  draw(d.rate_noise, m.rate.noise);
  std::vector<double> bias(static_cast<std::size_t>(axes));
  for (int i = 0; i < axes; ++i) {
    bias[static_cast<std::size_t>(i)] = m.rate.bias_of(i);
    draw(d.rate_bias, bias[static_cast<std::size_t>(i)]);
  }
  if (d.rate_bias) m.rate.bias = std::move(bias);
  draw(d.bias_walk, m.rate.bias_walk);
  const double u = r.uniform();
  if (d.delay) {
    const auto [lo, hi] = *d.delay;
    m.delay = uniform_int(u, lo, hi);
  }
  s.sensors = std::move(m);
}

sim::Scenario ensemble_member(const Job& job, std::uint64_t seed, std::int64_t k) {
  const EnsembleConfig& e = *job.ensemble;
  const sim::Scenario& base = ensemble_base(job);
  const sim::PlantKind& kind = *sim::find_plant_kind(job.plant.model);
  SplitMix64 r = SplitMix64::member(seed, static_cast<std::uint64_t>(k));
  const auto factor = [&](const std::optional<Distribution>& d) {
    const double u = r.uniform();  // consumed whether or not the scale is given
    return d ? d->draw(u) : 1.0;
  };

  // The draws in the order SPEC §12 fixes: 3 factors on the plant's uncertain parameters (its
  // inertia's axes), which each scaled parameter maps through its own distribution, then six
  // initial-state factors whatever the plant (a plant with fewer than six components uses the
  // first 2n, one with more would draw one per component), then one factor on every disturbance
  // amplitude.
  std::array<double, kParameterFactors> parameter_u{};
  for (double& u : parameter_u) u = r.uniform();  // consumed whether or not a scale is given
  ParameterFactors parameter_factors;
  for (const ParameterScale& p : e.parameter_scales) {
    std::array<double, kParameterFactors> f{};
    for (std::size_t i = 0; i < f.size(); ++i) f[i] = p.distribution.draw(parameter_u[i]);
    parameter_factors.emplace_back(p.parameter, f);
  }
  std::vector<double> state_factor(std::max<std::size_t>(6, base.initial_state.size()));
  for (double& f : state_factor) f = factor(e.initial_state_scale);
  const double d = factor(e.disturbance_scale);
  sim::Scenario s = scaled_base(job, parameter_factors, state_factor, d);
  s.name = base.name + "-" + std::to_string(k);

  if (e.faults) {
    const FaultDistribution& fd = *e.faults;
    const int count = uniform_int(r.uniform(), fd.count_lo, fd.count_hi);
    std::vector<int> available = fd.actuators;
    if (available.empty())
      for (int j = 1; j <= kind.actuators_of(job.plant.values); ++j) available.push_back(j);
    s.faults.clear();
    for (int slot = 0; slot < fd.count_hi; ++slot) {
      // The slot's 11 draws, in the normative order, all consumed.
      double u[11];
      for (double& v : u) v = r.uniform();
      if (slot >= count) continue;
      sim::Fault f;
      const std::size_t pick = std::min(
          available.size() - 1, static_cast<std::size_t>(std::floor(u[0] * available.size())));
      f.actuator = available[pick];
      available.erase(available.begin() + static_cast<long>(pick));
      f.type = kFaultTypeOrder[fd.type.pick(u[1])];
      f.onset = fd.onset ? fd.onset->draw(u[2]) : 0.5 * base.duration;
      f.profile.type = kProfileOrder[fd.profile.pick(u[3])];
      f.profile.rate = f.profile.type == sim::FaultProfileType::incipient ? fd.rate.draw(u[4]) : 1.0;
      switch (f.type) {
        case sim::FaultType::bias:
          f.offset = fd.offset.draw(u[5]);
          f.amplitude = fd.amplitude.draw(u[6]);
          f.frequency = fd.frequency.draw(u[7]);
          f.phase = fd.phase.draw(u[8]);
          break;
        case sim::FaultType::loss_of_effectiveness:
          f.fraction = std::clamp(fd.fraction.draw(u[9]), 0.0, 1.0);
          break;
        case sim::FaultType::stuck:
          f.value = fd.value.draw(u[10]);
          break;
      }
      s.faults.push_back(f);
    }
  }
  // SPEC §17: m actuator scales, then m misalignments, for a plant that declares them.
  const auto m = static_cast<std::size_t>(kind.actuators_of(job.plant.values));
  std::vector<double> scale_draws, misalignment_draws;
  if (kind.find_uncertain("actuator_scale"))
    for (std::size_t j = 0; j < m; ++j) {
      const double u = r.uniform();
      scale_draws.push_back(e.actuator_scale ? e.actuator_scale->draw(u) : 1.0);
    }
  if (kind.find_uncertain("actuator_misalignment"))
    for (std::size_t j = 0; j < m; ++j) {
      const double u = r.uniform();
      misalignment_draws.push_back(e.actuator_misalignment ? e.actuator_misalignment->draw(u)
                                                           : 0.0);
    }
  apply_actuator_draws(job, s, scale_draws, misalignment_draws);
  if (e.sensors) draw_sensors(*e.sensors, kind.axes, r, s);
  // The member's sensor noise (SPEC §18): stream k, of the base's seed if it gives one, else of
  // the ensemble's. Both are written out with the member, so that it draws the same noise
  // replayed alone or listed in a scenarios file (`ftctune ensemble`, evaluate's worst members).
  if (s.sensors) {
    s.sensors->seed = base.sensors && base.sensors->seed ? *base.sensors->seed : seed;
    s.sensors->stream = static_cast<std::uint64_t>(k);
    s.sensors->resolve(seed, static_cast<std::uint64_t>(k));
  }
  return s;
}

std::vector<sim::Scenario> expand_ensemble(const Job& job, std::optional<std::uint64_t> seed,
                                           std::optional<std::int64_t> count) {
  std::vector<sim::Scenario> members;
  if (!job.ensemble) return members;
  const std::int64_t n = count.value_or(job.ensemble->count);
  members.reserve(static_cast<std::size_t>(n));
  for (std::int64_t k = 0; k < n; ++k)
    members.push_back(ensemble_member(job, seed.value_or(job.ensemble->seed), k));
  return members;
}

// --- the JSON form -----------------------------------------------------------------------------

namespace {

const char* kind_name(Distribution::Kind k) {
  return k == Distribution::Kind::uniform ? "uniform" : "log_uniform";
}

// [lo, hi], two integers (clamped to [-1, 1e6], for the range checks to name); false after an
// error.
bool read_int_pair(const json& v, const std::string& path, int& lo, int& hi, Errors& e) {
  long long a = 0, b = 0;
  if (!v.is_array() || v.size() != 2 || !json_io::json_to_int(v[0], a) ||
      !json_io::json_to_int(v[1], b)) {
    e.push_back({path, "expected [lo, hi] (two integers), got " + json_io::json_type_name(v)});
    return false;
  }
  lo = static_cast<int>(std::clamp(a, -1LL, 1000000LL));
  hi = static_cast<int>(std::clamp(b, -1LL, 1000000LL));
  return true;
}

// A number (constant), {"uniform": [a, b]} or {"log_uniform": [a, b]}.
class DistributionShape final : public schema::Shape<Distribution> {
 public:
  // `positive`: what the distribution scales when it must be > 0 ("" = any sign).
  explicit DistributionShape(std::string doc, std::string positive = "")
      : doc_(std::move(doc)), positive_(std::move(positive)) {}

  void read(const json& j, const std::string& path, Distribution& out,
            Errors& errs) const override {
    if (j.is_number()) {
      out = Distribution::constant(j.get<double>());
      return;
    }
    const char* expected =
        "expected a number, {\"uniform\": [a, b]} or {\"log_uniform\": [a, b]}, got ";
    if (!j.is_object() || j.size() != 1 || !(j.contains("uniform") || j.contains("log_uniform"))) {
      errs.push_back({path, expected + json_io::json_type_name(j)});
      return;
    }
    const std::string key = j.begin().key();
    const json& v = j.begin().value();
    const std::string p = path + "/" + key;
    if (!v.is_array() || v.size() != 2 || !v[0].is_number() || !v[1].is_number()) {
      errs.push_back({p, "expected [a, b] (two numbers), got " + json_io::json_type_name(v)});
      return;
    }
    out.kind = key == "uniform" ? Distribution::Kind::uniform : Distribution::Kind::log_uniform;
    out.a = v[0].get<double>();
    out.b = v[1].get<double>();
  }
  void validate(const Distribution& d, const std::string& path, Errors& errs) const override {
    if (d.kind == Distribution::Kind::constant) {
      if (!std::isfinite(d.a))
        errs.push_back({path, "must be a finite number"});
      else if (!positive_.empty() && !(d.a > 0))
        errs.push_back({path, "must be > 0 (got " + json_io::number_text(d.a) + ")"});
      return;
    }
    const std::string p = path + "/" + kind_name(d.kind);
    if (!std::isfinite(d.a) || !std::isfinite(d.b)) {
      errs.push_back({p, "must hold two finite numbers"});
      return;
    }
    if (d.a > d.b)
      errs.push_back({p, "lower end " + json_io::number_text(d.a) + " is above upper end " +
                             json_io::number_text(d.b)});
    else if (!std::isfinite(d.b - d.a))  // a draw is a + (b - a) u (SPEC §12)
      errs.push_back({p, "is too wide: b - a is beyond the range of a double"});
    else if ((d.kind == Distribution::Kind::log_uniform || !positive_.empty()) && !(d.a > 0))
      errs.push_back({p + "/0", "must be > 0 for " +
                                    (d.kind == Distribution::Kind::log_uniform
                                         ? std::string("a log-uniform distribution")
                                         : "a scale of " + positive_) +
                                    " (got " + json_io::number_text(d.a) + ")"});
  }
  json write(const Distribution& d) const override {
    if (d.kind == Distribution::Kind::constant) return d.a;
    return {{kind_name(d.kind), {d.a, d.b}}};
  }
  json json_schema() const override {
    const json pair = {
        {"type", "array"}, {"items", {{"type", "number"}}}, {"minItems", 2}, {"maxItems", 2}};
    return {{"description", doc_},
            {"oneOf", json::array({{{"type", "number"}},
                                   {{"type", "object"},
                                    {"properties", {{"uniform", pair}}},
                                    {"required", {"uniform"}},
                                    {"additionalProperties", false}},
                                   {{"type", "object"},
                                    {"properties", {{"log_uniform", pair}}},
                                    {"required", {"log_uniform"}},
                                    {"additionalProperties", false}}})}};
  }

 private:
  std::string doc_;
  std::string positive_;
};

std::shared_ptr<const schema::Shape<SensorDistribution>> make_sensors_shape() {
  using D = SensorDistribution;
  auto o = std::make_shared<schema::Object<D>>(
      "Each member's sensors (SPEC §18), drawn after the actuator draws in this order: "
      "angle_noise, rate_noise, rate_bias (n draws), bias_walk, delay; absent: the base's");
  const auto dist = [](const char* doc) {
    return std::shared_ptr<const schema::Shape<Distribution>>(
        std::make_shared<DistributionShape>(doc));
  };
  o->optional_object("angle_noise", &D::angle_noise, dist("σ_a in rad (1σ), ≥ 0"), "");
  o->optional_object("rate_noise", &D::rate_noise, dist("σ_r in rad/s (1σ), ≥ 0"), "");
  o->optional_object("rate_bias", &D::rate_bias, dist("b_0 in rad/s, one draw per axis"), "");
  o->optional_object("bias_walk", &D::bias_walk, dist("σ_w in rad/s/√s, ≥ 0"), "");
  o->field({"delay", false,
            [](const json& v, const std::string& path, D& d, Errors& e) {
              int lo = 0, hi = 0;
              if (read_int_pair(v, path, lo, hi, e)) d.delay = std::pair<int, int>(lo, hi);
            },
            [](const D& d, const std::string& path, Errors& e) {
              if (!d.delay) return;
              const auto [lo, hi] = *d.delay;
              if (lo < 0 || hi > sim::SensorModel::kMaxDelay || lo > hi)
                e.push_back({path, "expected 0 <= lo <= hi <= " +
                                       std::to_string(sim::SensorModel::kMaxDelay) + ", got [" +
                                       std::to_string(lo) + ", " + std::to_string(hi) + "]"});
            },
            [](const D& d, json& obj) {
              if (d.delay) obj["delay"] = {d.delay->first, d.delay->second};
            },
            [] {
              return json{{"type", "array"},
                          {"items", {{"type", "integer"}, {"minimum", 0}}},
                          {"minItems", 2},
                          {"maxItems", 2},
                          {"description",
                           "[lo, hi]: a delay of lo + floor(u (hi - lo + 1)) samples"}};
            }});
  o->rule([](const D& d, const std::string& path, Errors& e) {
    for (const auto& [key, level] : {std::pair{"angle_noise", &d.angle_noise},
                                     std::pair{"rate_noise", &d.rate_noise},
                                     std::pair{"bias_walk", &d.bias_walk}})
      if (*level && (*level)->a < 0)
        e.push_back({path + "/" + key, "must be >= 0 (a noise level), got a lower end of " +
                                           json_io::number_text((*level)->a)});
  });
  return o;
}

// name → weight over a canonical list of names.
class ChoiceShape final : public schema::Shape<Choice> {
 public:
  ChoiceShape(std::vector<std::string> names, std::string doc)
      : names_(std::move(names)), doc_(std::move(doc)) {}

  void read(const json& j, const std::string& path, Choice& out, Errors& errs) const override {
    if (!j.is_object()) {
      errs.push_back(
          {path, "expected an object of name: weight, got " + json_io::json_type_name(j)});
      return;
    }
    out.weights.assign(names_.size(), 0.0);
    for (auto it = j.begin(); it != j.end(); ++it) {
      const std::string p = path + "/" + json_io::pointer_escape(it.key());
      const auto n = std::find(names_.begin(), names_.end(), it.key());
      if (n == names_.end()) {
        std::string known;
        for (const std::string& k : names_) known += (known.empty() ? "" : ", ") + k;
        errs.push_back({p, "unknown name (known: " + known + ")"});
      } else if (!it.value().is_number()) {
        errs.push_back({p, "expected a number, got " + json_io::json_type_name(it.value())});
      } else {
        out.weights[static_cast<std::size_t>(n - names_.begin())] = it.value().get<double>();
      }
    }
  }
  void validate(const Choice& c, const std::string& path, Errors& errs) const override {
    double total = 0.0;
    for (std::size_t i = 0; i < c.weights.size(); ++i) {
      if (!(std::isfinite(c.weights[i]) && c.weights[i] >= 0))
        errs.push_back({path + "/" + names_[i],
                        "must be a weight >= 0 (got " + json_io::number_text(c.weights[i]) + ")"});
      else
        total += c.weights[i];
    }
    if (!(total > 0)) errs.push_back({path, "weights must not all be zero"});
  }
  json write(const Choice& c) const override {
    json o = json::object();
    for (std::size_t i = 0; i < names_.size() && i < c.weights.size(); ++i)
      o[names_[i]] = c.weights[i];
    return o;
  }
  json json_schema() const override {
    json props = json::object();
    for (const std::string& n : names_) props[n] = {{"type", "number"}, {"minimum", 0}};
    return {{"type", "object"},
            {"properties", props},
            {"additionalProperties", false},
            {"minProperties", 1},
            {"description", doc_}};
  }

 private:
  std::vector<std::string> names_;
  std::string doc_;
};

template <class T>
using Obj = schema::Object<T>;

std::shared_ptr<const Obj<FaultDistribution>> make_faults_shape() {
  using F = FaultDistribution;
  auto o = std::make_shared<Obj<F>>("How each member's faults are drawn (they replace the base's)");
  o->field({"count", true,
            [](const json& v, const std::string& path, F& f, Errors& e) {
              read_int_pair(v, path, f.count_lo, f.count_hi, e);
            },
            [](const F&, const std::string&, Errors&) {},  // against the actuators: rule below
            [](const F& f, json& obj) {
              obj["count"] = {f.count_lo, f.count_hi};
            },
            [] {
              return json{{"type", "array"},
                          {"items", {{"type", "integer"}, {"minimum", 0}}},
                          {"minItems", 2},
                          {"maxItems", 2},
                          {"description", "[lo, hi]: lo + floor(u (hi - lo + 1)) faults"}};
            }});
  o->field({"actuators", false,
            [](const json& v, const std::string& path, F& f, Errors& e) {
              if (!v.is_array()) {
                e.push_back({path, "expected an array of actuator indices, got " +
                                       json_io::json_type_name(v)});
                return;
              }
              f.actuators.clear();
              if (v.empty())
                e.push_back({path,
                             "must list at least one actuator (leave the key out for all "
                             "of the plant's)"});
              for (std::size_t i = 0; i < v.size(); ++i) {
                long long a = 0;
                if (!json_io::json_to_int(v[i], a))
                  e.push_back({path + "/" + std::to_string(i),
                               "expected an integer, got " + json_io::json_type_name(v[i])});
                else
                  f.actuators.push_back(static_cast<int>(std::clamp(a, -1LL, 1000000LL)));
              }
            },
            [](const F&, const std::string&, Errors&) {},  // against the plant: job rule
            // None listed means every actuator: the key stays out (an empty list is refused).
            [](const F& f, json& obj) {
              if (!f.actuators.empty()) obj["actuators"] = f.actuators;
            },
            [] {
              return json{{"type", "array"},
                          {"items", {{"type", "integer"}, {"minimum", 1}}},
                          {"uniqueItems", true},
                          {"description",
                           "the actuators faults may hit, in listed order "
                           "(default all)"}};
            }});
  const auto choice = [](std::vector<std::string> names, std::string doc) {
    return std::make_shared<ChoiceShape>(std::move(names), std::move(doc));
  };
  o->object("type", &F::type,
            std::shared_ptr<const schema::Shape<Choice>>(
                choice({"bias", "loss_of_effectiveness", "stuck"}, "weights of the fault types")),
            "", schema::kRequired);
  o->optional_object("onset", &F::onset,
                     std::shared_ptr<const schema::Shape<Distribution>>(
                         std::make_shared<DistributionShape>("onset t_f in s")),
                     "default half the duration");
  o->object("profile", &F::profile,
            std::shared_ptr<const schema::Shape<Choice>>(
                choice({"abrupt", "incipient"}, "weights of the profiles; default abrupt only")),
            "");
  const std::pair<const char*, Distribution F::*> dists[] = {
      {"rate", &F::rate},           {"offset", &F::offset}, {"amplitude", &F::amplitude},
      {"frequency", &F::frequency}, {"phase", &F::phase},   {"fraction", &F::fraction},
      {"value", &F::value}};
  for (const auto& [name, member] : dists)
    o->object(name, member,
              std::shared_ptr<const schema::Shape<Distribution>>(
                  std::make_shared<DistributionShape>(std::string("the fault's ") + name)),
              "");
  o->rule([](const F& f, const std::string& path, Errors& e) {
    if (f.count_lo < 0 || f.count_hi < f.count_lo)
      e.push_back({path + "/count", "must be [lo, hi] with 0 <= lo <= hi (got [" +
                                        std::to_string(f.count_lo) + ", " +
                                        std::to_string(f.count_hi) + "])"});
    // a is each distribution's least value.
    if (f.profile.weights.size() > 1 && f.profile.weights[1] > 0 && !(f.rate.a > 0))
      e.push_back({path + "/rate", "must be > 0, the rate β of incipient faults (got " +
                                       json_io::number_text(f.rate.a) + ")"});
    if (f.onset && !(f.onset->a >= 0))
      e.push_back({path + "/onset", "must not draw onsets before 0 s (got " +
                                        json_io::number_text(f.onset->a) + ")"});
  });
  return o;
}

std::shared_ptr<const Obj<EnsembleConfig>> make_ensemble_shape() {
  using E = EnsembleConfig;
  auto o = std::make_shared<Obj<E>>(
      "Scenarios drawn from distributions (SPEC §12): member k copies the base and draws its "
      "scales and faults from its own random stream");
  o->field({"count", true,
            [](const json& v, const std::string& path, E& e, Errors& errs) {
              long long n = 0;
              if (!json_io::json_to_int(v, n))
                errs.push_back({path, "expected an integer, got " + json_io::json_type_name(v)});
              else
                e.count = n;
            },
            [](const E& e, const std::string& path, Errors& errs) {
              if (e.count < 1 || e.count > kMaxEnsembleCount)
                errs.push_back({path, "must be an integer in 1..1000000 (got " +
                                          std::to_string(e.count) + ")"});
            },
            [](const E& e, json& obj) { obj["count"] = e.count; },
            [] {
              return json{{"type", "integer"},
                          {"minimum", 1},
                          {"maximum", kMaxEnsembleCount},
                          {"description", "number of members"}};
            }});
  o->uint64("seed", &E::seed, "seed of the members' random streams");
  o->string("base", &E::base, "the scenario members copy (default the first)");
  // One scale per uncertain parameter of the registered plants (the job's plant must declare it,
  // job.cpp's validate_ensemble), on the first 3 draws of a member's stream.
  for (const runtime::UncertainKey& k : runtime::uncertain_keys()) {
    if (k.per_actuator) continue;  // drawn per actuator under its own name, below
    const std::string key = k.parameter + "_scale";
    const std::string parameter = k.parameter;
    auto shape = std::make_shared<const DistributionShape>(
        "factor on " + k.meaning + ", of the true " + k.parameter + " (" + k.models +
            "; 3 draws)",
        k.parameter);
    o->field({key, false,
              [parameter, shape](const json& v, const std::string& path, E& e, Errors& errs) {
                Distribution d{};
                shape->read(v, path, d, errs);
                std::erase_if(e.parameter_scales,
                              [&](const ParameterScale& p) { return p.parameter == parameter; });
                e.parameter_scales.push_back({parameter, d});
              },
              [parameter, shape](const E& e, const std::string& path, Errors& errs) {
                if (const Distribution* d = e.parameter_scale(parameter))
                  shape->validate(*d, path, errs);
              },
              [parameter, key, shape](const E& e, json& obj) {
                if (const Distribution* d = e.parameter_scale(parameter))
                  obj[key] = shape->write(*d);
              },
              [shape] { return shape->json_schema(); }});
  }
  for (const auto& [name, member, doc] :
       {std::tuple{"initial_state_scale", &E::initial_state_scale,
                   "factor on each initial-state component (2n draws)"},
        std::tuple{"disturbance_scale", &E::disturbance_scale,
                   "factor on every disturbance amplitude (1 draw)"}})
    o->optional_object(name, member,
                       std::shared_ptr<const schema::Shape<Distribution>>(
                           std::make_shared<DistributionShape>(doc)),
                       "");
  o->optional_object(
      "actuator_scale", &E::actuator_scale,
      std::shared_ptr<const schema::Shape<Distribution>>(std::make_shared<DistributionShape>(
          "factor on each actuator's effectiveness in the simulated plant (rigid_body, "
          "multirotor; m draws after the faults' draws)",
          "an actuator's effectiveness")),
      "");
  o->optional_object(
      "actuator_misalignment", &E::actuator_misalignment,
      std::shared_ptr<const schema::Shape<Distribution>>(std::make_shared<DistributionShape>(
          "angle in rad added to each actuator's misalignment in the simulated plant "
          "(rigid_body; m draws after the actuator scales' draws)")),
      "");
  o->optional_object("faults", &E::faults,
                     std::shared_ptr<const schema::Shape<FaultDistribution>>(make_faults_shape()),
                     "");
  o->optional_object("sensors", &E::sensors, make_sensors_shape(), "");
  o->choice("unrecoverable", &E::unrecoverable,
            {{"exclude", Unrecoverable::exclude}, {"include", Unrecoverable::include}},
            "whether members no gains can control count in the objective");
  return o;
}

}  // namespace

const Distribution* EnsembleConfig::parameter_scale(std::string_view parameter) const {
  for (const ParameterScale& p : parameter_scales)
    if (p.parameter == parameter) return &p.distribution;
  return nullptr;
}

namespace job_detail {

std::shared_ptr<const schema::Shape<EnsembleConfig>> ensemble_shape() {
  // Its scales are the uncertain parameters of the plants a job can name now.
  static const auto shape = std::make_shared<const schema::Regenerated<EnsembleConfig>>(
      [] { return std::shared_ptr<const schema::Shape<EnsembleConfig>>(make_ensemble_shape()); },
      sim::plant_kinds_generation);
  return shape;
}

}  // namespace job_detail
}  // namespace ftc::tune
