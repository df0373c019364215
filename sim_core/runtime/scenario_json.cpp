// The scenario's JSON form (runtime/scenario_json.hpp).
#include "ftc/runtime/scenario_json.hpp"

#include <algorithm>
#include <limits>
#include <nlohmann/json.hpp>
#include <string_view>

#include "ftc/runtime/json_reader.hpp"
#include "ftc/sim/input_error.hpp"
#include "ftc/sim/plant_plugin.hpp"
#include "vehicle_json.hpp"

namespace ftc::runtime {

using nlohmann::json;
using schema::Errors;
using schema::kRequired;

namespace {

template <class T>
using Obj = schema::Object<T>;
template <class T>
using Ptr = std::shared_ptr<const schema::Shape<T>>;

std::string field_doc(const char* description, const char* unit) {
  return *unit ? std::string(description) + " (" + unit + ")" : std::string(description);
}

// A numeric field of a sim struct from its table; checked by the struct's validate().
template <class T>
void add_number(Obj<T>& o, const sim::NumberField<T>& f, schema::Presence p = schema::kOptional) {
  o.number(f.name, f.member, f.range, field_doc(f.description, f.unit), p, false);
}
template <class T>
void add_integer(Obj<T>& o, const sim::IntegerField<T>& f, schema::Presence p = schema::kOptional) {
  o.integer(f.name, f.member, {f.min, f.max}, f.description, p, false);
}

// --- scenarios --------------------------------------------------------------------------------

Ptr<sim::DisturbanceTerm> make_disturbance_shape() {
  using D = sim::DisturbanceTerm;
  auto o = std::make_shared<Obj<D>>("One sinusoid of Δ on one axis: amplitude · shape(ω t + φ)");
  add_integer(*o, D::axis_field(), kRequired);
  o->choice("shape", &D::shape, {{"sin", sim::Shape::sin}, {"cos", sim::Shape::cos}}, "sin or cos");
  for (const sim::NumberField<D>& f : D::number_fields())
    add_number(*o, f, std::string_view(f.name) == "phase" ? schema::kOptional : kRequired);
  return o;
}

Ptr<sim::DisturbanceTerm> disturbance_shape() {
  static const Ptr<sim::DisturbanceTerm> shape = make_disturbance_shape();
  return shape;
}

Ptr<sim::FaultProfile> make_profile_shape() {
  using P = sim::FaultProfile;
  auto v = std::make_shared<schema::Variant<P>>(
      "type", [](const P& p) { return std::string(sim::to_string(p.type)); },
      [](P& p, const std::string& name) {
        p.type =
            name == "abrupt" ? sim::FaultProfileType::abrupt : sim::FaultProfileType::incipient;
      },
      "How the fault grows after its onset: abrupt (ρ = 1) or incipient (ρ = 1 - exp(-β τ))");
  v->add("abrupt", std::make_shared<Obj<P>>());
  auto incipient = std::make_shared<Obj<P>>();
  add_number(*incipient, P::rate_field(), kRequired);
  v->add("incipient", std::move(incipient));
  return v;
}

Ptr<sim::FaultProfile> profile_shape() {
  static const Ptr<sim::FaultProfile> shape = make_profile_shape();
  return shape;
}

Ptr<sim::Fault> make_fault_shape() {
  using F = sim::Fault;
  const Ptr<sim::FaultProfile> profile = profile_shape();
  auto v = std::make_shared<schema::Variant<F>>(
      "type", [](const F& f) { return std::string(sim::to_string(f.type)); },
      [](F& f, const std::string& name) {
        for (sim::FaultType t :
             {sim::FaultType::bias, sim::FaultType::loss_of_effectiveness, sim::FaultType::stuck})
          if (name == sim::to_string(t)) f.type = t;
      },
      "An actuator fault: u_j = u_d,j + ρ(t - onset) δu_j");
  const std::pair<sim::FaultType, const char*> cases[] = {
      {sim::FaultType::bias, "a bias offset + amplitude cos(frequency t + phase)"},
      {sim::FaultType::loss_of_effectiveness, "the actuator loses a fraction of its command"},
      {sim::FaultType::stuck, "the actuator's output is frozen at value"}};
  for (const auto& [type, what] : cases) {
    auto o = std::make_shared<Obj<F>>(what);
    add_integer(*o, F::actuator_field(), kRequired);
    for (const sim::NumberField<F>& f : F::common_fields()) add_number(*o, f, kRequired);
    o->object("profile", &F::profile, profile, "");
    for (const sim::NumberField<F>& f : F::type_fields(type))
      add_number(*o, f, type == sim::FaultType::bias ? schema::kOptional : kRequired);
    v->add(sim::to_string(type), std::move(o));
  }
  return v;
}

Ptr<sim::Fault> fault_shape() {
  static const Ptr<sim::Fault> shape = make_fault_shape();
  return shape;
}

Ptr<sim::ActuatorModel> make_actuator_shape() {
  using A = sim::ActuatorModel;
  auto o = std::make_shared<Obj<A>>(
      "The actuators' dynamics (docs/model.md): each actuator's output follows its command, "
      "clamped to the actuator's range, with a first-order lag and a rate limit; the faults and "
      "the saturation act on that output. Give one or both; absent: the command drives the plant");
  o->optional_number("time_constant", &A::time_constant, A::kTimeConstantRange,
                     "τ of the lag τ du_a/dt = u_c - u_a (s), at least 2 · sample_time / "
                     "substeps; absent: no lag",
                     false);
  o->optional_number("rate_limit", &A::rate_limit, A::kRateLimitRange,
                     "|du_a/dt| <= rate_limit (units of u per s); absent: no limit", false);
  return o;
}

Ptr<sim::ActuatorModel> actuator_shape() {
  static const Ptr<sim::ActuatorModel> shape = make_actuator_shape();
  return shape;
}

// A number (for every actuator or axis) or an array of numbers (one each), kept as a list of one
// or of several; checked against the plant by the struct's validate().
template <class T, class Get, class ConstGet>
typename Obj<T>::Field number_or_list(std::string key, Get get, ConstGet cget, schema::Range range,
                                      std::string each, std::string doc) {
  return {key, false,
          [get, each](const json& v, const std::string& path, T& t, Errors& e) {
            if (v.is_number()) {
              double x = 0.0;
              if (schema::detail::read_number(v, path, x, e)) get(t) = {x};
              return;
            }
            if (!v.is_array() || v.empty()) {
              e.push_back({path, "expected a number or an array of numbers (one per " + each +
                                     "), got " + json_io::json_type_name(v)});
              return;
            }
            std::vector<double> x(v.size());
            for (std::size_t i = 0; i < v.size(); ++i)
              if (!schema::detail::read_number(v[i], path + "/" + std::to_string(i), x[i], e))
                return;
            get(t) = std::move(x);
          },
          [](const T&, const std::string&, Errors&) {},  // against the plant: validate()
          [cget, key](const T& t, json& obj) {
            const std::vector<double>& x = cget(t);
            if (x.size() == 1)
              obj[key] = x[0];
            else if (x.size() > 1)
              obj[key] = x;
          },
          [range, doc] {
            json item = {{"type", "number"}};
            schema::annotate(range, item);
            return json{{"description", doc},
                        {"oneOf", json::array({item, {{"type", "array"},
                                                      {"items", item},
                                                      {"minItems", 1}}})}};
          }};
}

// --- sensors (SPEC §18) ------------------------------------------------------------------------

Ptr<sim::AccelerationSensor> make_acceleration_shape() {
  using A = sim::AccelerationSensor;
  auto accel = std::make_shared<schema::Variant<A>>(
      "source",
      [](const A& a) {
        return std::string(a.source == sim::AccelerationSource::ideal ? "ideal" : "differentiated");
      },
      [](A& a, const std::string& name) {
        a.source = name == "ideal" ? sim::AccelerationSource::ideal
                                   : sim::AccelerationSource::differentiated;
      },
      "The acceleration the controller reads: ideal (the loop's exact a_k, undelayed) or "
      "differentiated ((X2m_k - X2m_{k-1}) / Ts through a first-order low-pass, delayed as the "
      "other measurements)");
  accel->add("ideal", std::make_shared<Obj<A>>());
  auto diff = std::make_shared<Obj<A>>();
  diff->number("time_constant", &A::time_constant, sim::SensorModel::kNoiseRange,
               "τ of the low-pass (s); 0: none", schema::kOptional, false);
  accel->add("differentiated", std::move(diff));
  return accel;
}

}  // namespace

Ptr<sim::AccelerationSensor> acceleration_shape() {
  static const Ptr<sim::AccelerationSensor> shape = make_acceleration_shape();
  return shape;
}

namespace {

Ptr<sim::SensorModel> make_sensors_shape() {
  using M = sim::SensorModel;
  const schema::Range noise = M::kNoiseRange;
  auto angle = std::make_shared<Obj<sim::AngleSensor>>("The attitude measurement X1m");
  angle->number("noise", &sim::AngleSensor::noise, noise, "σ_a, white noise (rad, 1σ)",
                schema::kOptional, false);
  angle->number("quantization", &sim::AngleSensor::quantization, noise,
                "Q_a, the measurement rounded to a multiple of it (rad); 0: none",
                schema::kOptional, false);
  using R = sim::RateSensor;
  auto rate = std::make_shared<Obj<R>>("The rate measurement X2m");
  rate->number("noise", &R::noise, noise, "σ_r, white noise (rad/s, 1σ)", schema::kOptional,
               false);
  rate->field(number_or_list<R>(
      "bias", [](R& r) -> std::vector<double>& { return r.bias; },
      [](const R& r) -> const std::vector<double>& { return r.bias; }, schema::Range::any(),
      "axis", "b_0, the bias at t = 0 (rad/s): one number for every axis or one per axis; "
              "default 0"));
  rate->number("bias_walk", &R::bias_walk, noise,
               "σ_w, the bias's random walk b_{k+1} = b_k + σ_w √Ts z (rad/s/√s)",
               schema::kOptional, false);
  rate->number("quantization", &R::quantization, noise,
               "Q_r, the measurement rounded to a multiple of it (rad/s); 0: none",
               schema::kOptional, false);

  auto o = std::make_shared<Obj<M>>(
      "What the controller reads (SPEC §18, docs/model.md): noisy, biased, quantised and "
      "delayed attitude and rates, and the acceleration. The metrics measure the true state. "
      "Absent: the exact state");
  o->optional_uint64("seed", &M::seed,
                     "the noise stream's seed; absent: 1, or the ensemble's seed for its "
                     "members");
  o->optional_uint64(
      "stream", &M::stream,
      "the noise stream's index i (SPEC §18's s0 = mix(seed XOR mix(0x53454E53 + i + 1))); "
      "absent: the scenario's index among the job's scenarios. An ensemble member is written "
      "with its own, so that it draws its noise when replayed alone");
  o->object("angle", &M::angle, Ptr<sim::AngleSensor>(angle), "");
  o->object("rate", &M::rate, Ptr<R>(rate), "");
  o->integer("delay", &M::delay, {0, M::kMaxDelay},
             "d: the controller at sample k reads the measurements of sample max(0, k - d)",
             schema::kOptional, false);
  o->object("acceleration", &M::acceleration, acceleration_shape(), "");
  return o;
}

Ptr<sim::SensorModel> sensors_shape() {
  static const Ptr<sim::SensorModel> shape = make_sensors_shape();
  return shape;
}

Ptr<sim::Scenario> make_scenario_shape() {
  using S = sim::Scenario;
  auto o = std::make_shared<Obj<S>>(
      "A closed-loop fault scenario: run length, sampling, initial state, disturbance, faults");
  o->string("name", &S::name, "unique within the job; names output files", kRequired, {},
            kNamePattern);
  for (const sim::NumberField<S>& f : S::number_fields())
    add_number(*o, f, std::string_view(f.name) == "duration" ? kRequired : schema::kOptional);
  add_integer(*o, S::substeps_field());
  o->number_list("initial_state", &S::initial_state, schema::Range::any(),
                 "X(0) = (X1, X2), 2n numbers; default the plant's", schema::kOptional, false);
  o->array("disturbance", &S::disturbance, disturbance_shape(), "Δ(t), a sum of sinusoids");
  o->array("faults", &S::faults, fault_shape(), "actuator faults; they add up");
  // A number (every actuator's limit) or one per actuator; checked by Scenario::validate.
  o->field(number_or_list<S>(
      "saturation", [](S& s) -> std::vector<double>& { return s.saturation.values; },
      [](const S& s) -> const std::vector<double>& { return s.saturation.values; },
      S::kSaturationRange, "actuator",
      "|u_j| <= the actuator's limit, applied to the command and again after the faults (so a "
      "weakened actuator delivers at most (1 - fraction) times it): one number for every "
      "actuator or one per actuator; absent: the plant's own limits only"));
  o->optional_object("actuator", &S::actuator, actuator_shape(), "");
  o->optional_object("sensors", &S::sensors, sensors_shape(), "");
  // Model mismatch: the true values of each parameter a registered plant declares uncertain,
  // under the parameter's name (the job's plant must declare it: validate_job).
  for (const UncertainKey& k : uncertain_keys()) {
    const std::string key = k.parameter;
    o->field(
        {key, false,
         [key, k](const json& v, const std::string& path, S& s, Errors& e) {
           std::vector<double> tensor;  // a 3×3 true inertia (rigid_body, multirotor)
           if (k.tensor && detail::read_tensor_values(v, path, tensor, e)) {
             if (!tensor.empty()) s.set_true_value(key, std::move(tensor));
             return;
           }
           if (!v.is_array()) {
             e.push_back({path, "expected an array of numbers, got " + json_io::json_type_name(v)});
             return;
           }
           std::vector<double> x(v.size());
           for (std::size_t i = 0; i < v.size(); ++i)
             if (!schema::detail::read_number(v[i], path + "/" + std::to_string(i), x[i], e))
               return;
           s.set_true_value(key, std::move(x));
         },
         [](const S&, const std::string&, Errors&) {},  // against the plant: job rule
         [key](const S& s, json& obj) {
           if (const std::vector<double>* v = s.true_value(key)) obj[key] = *v;
         },
         [k] {
           json item = {{"type", "number"}};
           std::string unit;
           if (k.declared) {
             schema::annotate(k.declared->range, item);
             if (!k.declared->unit.empty()) unit = " (" + k.declared->unit + ")";
           }
           return json{
               {"type", "array"},
               {"items", item},
               {"description", "the true " + k.parameter + " of the simulated plant" + unit +
                                   (k.per_actuator ? ", one per actuator" : "") +
                                   ", for a plant that declares it uncertain (" + k.models +
                                   "); the controller keeps the job's plant as its "
                                   "model. Absent: the plant's"}};
         }});
  }
  return o;
}

}  // namespace

Ptr<sim::Scenario> scenario_shape() {
  // Its true values' keys are the uncertain parameters of the plants a job can name now.
  static const Ptr<sim::Scenario> shape =
      std::make_shared<const schema::Regenerated<sim::Scenario>>(make_scenario_shape,
                                                                 sim::plant_kinds_generation);
  return shape;
}

json to_json(const sim::Scenario& s) { return scenario_shape()->write(s); }

sim::Scenario scenario_from_json(const json& j, const std::string& source) {
  sim::Scenario s;
  Errors errs;
  schema::read(*scenario_shape(), j, "", s, errs);
  throw_if_errors(source, std::move(errs));
  // Read alone, a scenario's noise stream is its own seed (default 1) and index (default 0).
  if (s.sensors) s.sensors->resolve(1, 0);
  return s;
}

std::vector<UncertainKey> uncertain_keys() {
  std::vector<UncertainKey> out;
  for (const sim::PlantKind* kp : sim::all_plant_kinds()) {
    const sim::PlantKind& kind = *kp;
    for (const sim::UncertainParameter& u : kind.uncertain) {
      const auto known = std::find_if(out.begin(), out.end(), [&](const UncertainKey& k) {
        return k.parameter == u.parameter;
      });
      if (known != out.end()) {
        known->models += ", " + kind.model;
        // A tensor where any plant takes one (the spacecraft's inertia is 3 moments, the
        // rigid body's a tensor or 3 moments).
        known->tensor = known->tensor || u.scaling == sim::Scaling::congruence;
        continue;
      }
      const sim::PlantParameter* declared = nullptr;
      for (const sim::PlantParameter& p : kind.parameters)
        if (p.name == u.parameter) declared = &p;
      out.push_back({u.parameter, kind.model, u.meaning, declared, u.per_actuator,
                     u.scaling == sim::Scaling::congruence});
    }
  }
  return out;
}

}  // namespace ftc::runtime
