#include "ftc/tune/job/job.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <nlohmann/json.hpp>
#include <set>
#include <tuple>

#include "ftc/runtime/controller_json.hpp"
#include "ftc/runtime/json_reader.hpp"
#include "ftc/runtime/plant_json.hpp"
#include "ftc/runtime/scenario_json.hpp"
#include "ftc/runtime/schema.hpp"
#include "ftc/tune/io/files.hpp"
#include "ftc/tune/job/ensemble.hpp"
#include "ftc/tune/optimizers/pagmo.hpp"
#include "job/shapes.hpp"

namespace ftc::tune {

using nlohmann::json;
using schema::Errors;
using schema::kRequired;

namespace {

template <class T>
using Obj = schema::Object<T>;
template <class T>
using Ptr = std::shared_ptr<const schema::Shape<T>>;

void append(Errors& to, Errors from) {
  to.insert(to.end(), std::make_move_iterator(from.begin()), std::make_move_iterator(from.end()));
}

constexpr std::size_t kMaxNameLength = 100;
bool safe_name(const std::string& s) {
  if (s.empty() || s.size() > kMaxNameLength || s[0] == '.') return false;
  for (char c : s)
    if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-' || c == '.'))
      return false;
  return true;
}
using runtime::kNamePattern;
using runtime::scenario_shape;

// --- objective and tuning ---------------------------------------------------------------------

// The window, aggregate, q, alpha and window_from fields that an objective and a goal share.
template <class O>
void add_window_field(Obj<O>& o) {
  // [t0, t1] in s; t1 may be null, meaning "to the end of each scenario".
  o.field({"window", false,
           [](const json& w, const std::string& path, O& out, Errors& e) {
             if (!w.is_array() || w.size() != 2 || !w[0].is_number() ||
                 !(w[1].is_number() || w[1].is_null()))
               e.push_back(
                   {path, "expected [start, end] in seconds, got " + json_io::json_type_name(w)});
             else
               out.window = {w[0].get<double>(), w[1].is_null()
                                                     ? std::numeric_limits<double>::infinity()
                                                     : w[1].get<double>()};
           },
           [](const O&, const std::string&, Errors&) {},  // against the scenarios: job rule
           [](const O& obj, json& out) {
             out["window"] = json::array({obj.window.t0, json_io::json_number(obj.window.t1)});
           },
           [] {
             return json{
                 {"type", "array"},
                 {"prefixItems", json::array({{{"type", "number"}, {"minimum", 0}},
                                              {{"type", json::array({"number", "null"})}}})},
                 {"minItems", 2},
                 {"maxItems", 2},
                 {"description", "[start, end) in s; end null = the end of the run"}};
           }});
}

template <class O>
void add_aggregate_fields(Obj<O>& o) {
  o.choice("aggregate", &O::aggregate,
           {{"mean", Aggregate::mean},
            {"max", Aggregate::max},
            {"quantile", Aggregate::quantile},
            {"cvar", Aggregate::cvar}},
           "how the scenarios' values combine; quantile and cvar are the robust ones");
  // q, alpha and window_from appear in the resolved job only where they matter, so that jobs
  // without them keep their canonical form (and their hash) from before these keys existed.
  const auto conditional = [](const char* key, double O::*m, schema::Range r, Aggregate when,
                              const char* doc) -> typename Obj<O>::Field {
    return {key,
            false,
            [m](const json& v, const std::string& path, O& obj, Errors& e) {
              schema::detail::read_number(v, path, obj.*m, e);
            },
            [m, r](const O& obj, const std::string& path, Errors& e) {
              if (std::string msg = r.check(obj.*m); !msg.empty()) e.push_back({path, msg});
            },
            [m, key, when](const O& obj, json& out) {
              if (obj.aggregate == when) out[key] = obj.*m;
            },
            [r, doc] {
              json s = schema::detail::number_schema(doc, r);
              s["default"] = 0.9;
              return s;
            }};
  };
  o.field(conditional("q", &O::q, schema::Range::half_open_unit(), Aggregate::quantile,
                      "the quantile q in (0, 1] of aggregate quantile"));
  o.field(conditional("alpha", &O::alpha, {0.0, false, 1.0, true}, Aggregate::cvar,
                      "alpha in [0, 1) of aggregate cvar: the mean of the worst 1 - alpha"));
  o.field({"window_from", false,
           [](const json& v, const std::string& path, O& obj, Errors& e) {
             if (!v.is_string())
               e.push_back({path, "expected a string, got " + json_io::json_type_name(v)});
             else if (v == "start")
               obj.window_from = WindowFrom::start;
             else if (v == "first_fault")
               obj.window_from = WindowFrom::first_fault;
             else
               e.push_back({path, schema::detail::choice_error({"start", "first_fault"},
                                                               v.get<std::string>())});
           },
           [](const O&, const std::string&, Errors&) {},
           [](const O& obj, json& out) {
             if (obj.window_from == WindowFrom::first_fault) out["window_from"] = "first_fault";
           },
           [] {
             return json{{"type", "string"},
                         {"enum", {"start", "first_fault"}},
                         {"default", "start"},
                         {"description",
                          "measure the window from each run's start or from each scenario's "
                          "earliest fault onset"}};
           }});
}

template <class O>
void check_aggregate_keys(const O& obj, const std::string& path, Errors& e) {
  if (obj.aggregate != Aggregate::quantile && obj.q != 0.9)
    e.push_back({path + "/q", "is used only with aggregate \"quantile\""});
  if (obj.aggregate != Aggregate::cvar && obj.alpha != 0.9)
    e.push_back({path + "/alpha", "is used only with aggregate \"cvar\""});
}

// --- metrics: names, scopes and settings, all from the metrics record (kMetricFields) --------

// The fields `can` marks (goal, objective), by name, in the table's order.
std::vector<std::pair<std::string, MetricRef>> metric_choices(bool sim::MetricField::*can) {
  std::vector<std::pair<std::string, MetricRef>> out;
  for (const sim::MetricField& f : sim::kMetricFields)
    if (f.*can) out.emplace_back(std::string(f.name), &f);
  return out;
}

// Names in words: "a", "a or b", "a, b or c" (`last`: "or", "and").
std::string in_words(const std::vector<std::string>& names, const char* last) {
  std::string s;
  for (std::size_t i = 0; i < names.size(); ++i)
    s += (i == 0 ? "" : i + 1 == names.size() ? std::string(" ") + last + " " : ", ") + names[i];
  return s;
}

// The names of the fields that `keep` keeps, in the table's order.
template <class Keep>
std::vector<std::string> metric_names(Keep keep, const char* quote = "") {
  std::vector<std::string> out;
  for (const sim::MetricField& f : sim::kMetricFields)
    if (keep(f)) out.push_back(quote + std::string(f.name) + quote);
  return out;
}

// A setting a metric is measured against (MetricField::setting): its key in a goal, its key in
// the job's metrics block, and where each is held.
struct SettingKeys {
  sim::MetricSetting setting;
  const char* key;
  const char* job_key;
  std::optional<double> GoalConfig::*own;
  std::optional<double> MetricsConfig::*from_job;
};
constexpr SettingKeys kSettingKeys[] = {
    {sim::MetricSetting::settling_threshold, "threshold", "settling_threshold",
     &GoalConfig::threshold, &MetricsConfig::settling_threshold},
    {sim::MetricSetting::steady_state_tail, "tail", "steady_state_tail", &GoalConfig::tail,
     &MetricsConfig::steady_state_tail}};

// The metrics measured against setting `s`, quoted or not, in words ("settling_time").
std::string metrics_using(sim::MetricSetting s, const char* quote = "") {
  return in_words(
      metric_names([s](const sim::MetricField& f) { return f.goal && f.setting == s; }, quote),
      "or");
}

// The metrics that can be the objective, in words ("ise, iae or itae").
std::string objective_metrics() {
  return in_words(metric_names([](const sim::MetricField& f) { return f.objective; }), "or");
}

Ptr<ObjectiveConfig> make_objective_shape() {
  using O = ObjectiveConfig;
  auto o = std::make_shared<Obj<O>>("What a candidate is scored by");
  o->choice("metric", &O::metric, metric_choices(&sim::MetricField::objective),
            "the metric measured over the window: " + objective_metrics());
  add_window_field(*o);
  add_aggregate_fields(*o);
  o->rule(
      [](const O& obj, const std::string& path, Errors& e) { check_aggregate_keys(obj, path, e); });
  return o;
}

Ptr<GoalConfig> make_goal_shape() {
  using G = GoalConfig;
  auto o = std::make_shared<Obj<G>>(
      "A goal: a metric in a window aggregated over the scenarios, minimised (\"minimize\": "
      "true, a soft goal) or kept at most a limit (\"at_most\", a hard goal)");
  const auto goal_in = [](bool windowed) {
    return [windowed](const sim::MetricField& f) {
      return f.goal && (f.scope == sim::MetricScope::window) == windowed;
    };
  };
  o->choice("metric", &G::metric, metric_choices(&sim::MetricField::goal),
            in_words(metric_names(goal_in(true)), "and") + " in the window; " +
                in_words(metric_names(goal_in(false)), "and") + " over the whole run",
            kRequired);
  add_window_field(*o);
  add_aggregate_fields(*o);
  o->field({"minimize", false,
            [](const json& v, const std::string& path, G& g, Errors& e) {
              if (!v.is_boolean())
                e.push_back({path, "expected true, got " + json_io::json_type_name(v)});
              else if (!v.get<bool>())
                e.push_back({path, "must be true when given (a limit is \"at_most\")"});
              else
                g.minimize = true;
            },
            [](const G&, const std::string&, Errors&) {},
            [](const G& g, json& out) {
              if (g.minimize) out["minimize"] = true;
            },
            [] {
              return json{{"const", true}, {"description", "a soft goal: the search minimises it"}};
            }});
  o->optional_number("at_most", &G::at_most, schema::Range::positive(),
                     "a hard goal: the limit the aggregate must not exceed (> 0)");
  o->optional_number("threshold", &G::threshold, schema::Range::positive(),
                     metrics_using(sim::MetricSetting::settling_threshold) +
                         " only: rad, ‖e‖ below it counts as settled (default: the job's "
                         "metrics.settling_threshold)");
  o->optional_number("tail", &G::tail, schema::Range::positive(),
                     metrics_using(sim::MetricSetting::steady_state_tail) +
                         " only: s, the tail of the window it averages (default: the job's "
                         "metrics.steady_state_tail)");
  o->rule([](const G& g, const std::string& path, Errors& e) {
    check_aggregate_keys(g, path, e);
    if (!g.minimize && !g.at_most)
      e.push_back({path,
                   "needs \"minimize\": true (a soft goal) or \"at_most\": a limit (a "
                   "hard goal)"});
    else if (g.minimize && g.at_most)
      e.push_back({path + "/at_most",
                   "a goal is minimised or limited, not both; give the limit "
                   "as a second goal"});
    for (const SettingKeys& k : kSettingKeys)
      if (g.*k.own && g.metric->setting != k.setting)
        e.push_back(
            {path + "/" + k.key, "is used only with metric " + metrics_using(k.setting, "\"")});
    if (!g.windowed() &&
        (g.window.t0 != 0.0 || std::isfinite(g.window.t1) || g.window_from != WindowFrom::start))
      e.push_back({path + "/window", std::string(g.metric->name) +
                                         " is measured over the whole run; it takes no window"});
  });
  return o;
}

Ptr<GoalConfig> goal_shape() {
  static const Ptr<GoalConfig> shape = make_goal_shape();
  return shape;
}

Ptr<ObjectiveConfig> objective_shape() {
  static const Ptr<ObjectiveConfig> shape = make_objective_shape();
  return shape;
}

Ptr<MetricsConfig> make_metrics_shape() {
  using M = MetricsConfig;
  auto o = std::make_shared<Obj<M>>(
      "What the settling time and the steady-state error are measured against (without them "
      "both are null)");
  o->optional_number("settling_threshold", &M::settling_threshold, schema::Range::positive(),
                     "rad: the run has settled once ‖e‖ stays below it, from the first fault on");
  o->optional_number("steady_state_tail", &M::steady_state_tail, schema::Range::positive(),
                     "s: the steady-state error is the mean ‖e‖ over each window's last "
                     "steady_state_tail seconds (the whole window if it is shorter)");
  o->optional_number("drift_warning", &M::drift_warning, schema::Range::positive(),
                     "rad (the plant's position unit): run warns when the tuned loop ends a "
                     "listed scenario farther from the reference than it started and than this "
                     "(default 0.1)");
  o->optional_number("control_tv_warning", &M::control_tv_warning, schema::Range::positive(),
                     "run warns when the tuned gains' control TV on the listed scenarios is more "
                     "than this many times the job's own gains' (default 3)");
  return o;
}

Ptr<MetricsConfig> metrics_shape() {
  static const Ptr<MetricsConfig> shape = make_metrics_shape();
  return shape;
}

// Rank of a parameter in the controller field table: the decision vector's order.
std::size_t field_rank(const std::string& name) {
  const auto fields = sim::controller_fields();
  for (std::size_t i = 0; i < fields.size(); ++i)
    if (name == fields[i].name) return i;
  return fields.size();
}

Ptr<TuningConfig> make_tuning_shape() {
  using T = TuningConfig;
  auto o = std::make_shared<Obj<T>>("What to tune, with which algorithm and seed");
  o->field(
      {"parameters", true,
       [](const json& pj, const std::string& pp, T& t, Errors& e) {
         if (!pj.is_object()) {
           e.push_back({pp, "expected an object of name: [lower, upper], got " +
                                json_io::json_type_name(pj)});
           return;
         }
         for (auto it = pj.begin(); it != pj.end(); ++it) {
           const std::string bp = pp + "/" + json_io::pointer_escape(it.key());
           ParameterBounds b{it.key()};
           const json* v = &it.value();
           std::string vp = bp;
           if (v->is_object()) {  // {"bounds": [lower, upper], "scale": "linear" | "log"}
             for (auto k = v->begin(); k != v->end(); ++k)
               if (k.key() != "bounds" && k.key() != "scale")
                 e.push_back({bp + "/" + json_io::pointer_escape(k.key()),
                              "unknown key (allowed here: bounds, scale)"});
             if (const auto s = v->find("scale"); s != v->end()) {
               if (*s == "log")
                 b.scale = Scale::log;
               else if (*s != "linear")
                 e.push_back(
                     {bp + "/scale", "must be \"linear\" or \"log\" (got " + s->dump() + ")"});
             }
             if (!v->contains("bounds")) {
               e.push_back({bp + "/bounds", "is required"});
               continue;
             }
             vp = bp + "/bounds";
             v = &(*v)["bounds"];
           }
           if (!v->is_array() || v->size() != 2 || !(*v)[0].is_number() || !(*v)[1].is_number()) {
             e.push_back({vp, "expected [lower, upper] (two numbers), got " +
                                  (v->is_array() ? "an array of " + std::to_string(v->size())
                                                 : json_io::json_type_name(*v))});
             continue;
           }
           b.lower = (*v)[0].get<double>();
           b.upper = (*v)[1].get<double>();
           t.parameters.push_back(b);
         }
         // JSON objects are unordered: fix the decision-vector order as that of the
         // controller field table (Kp before Ki), unknown names last, so it never depends
         // on the file.
         std::stable_sort(t.parameters.begin(), t.parameters.end(),
                          [](const ParameterBounds& a, const ParameterBounds& b) {
                            const std::size_t ra = field_rank(a.name), rb = field_rank(b.name);
                            return ra != rb ? ra < rb : a.name < b.name;
                          });
       },
       [](const T&, const std::string&, Errors&) {},  // against the controller: job rule
       [](const T& t, json& out) {
         json params = json::object();
         for (const ParameterBounds& b : t.parameters)
           params[b.name] = b.scale == Scale::linear
                                ? json{b.lower, b.upper}
                                : json{{"bounds", {b.lower, b.upper}}, {"scale", "log"}};
         out["parameters"] = params;
       },
       [] {
         json names = json::array();
         for (const sim::ControllerField& f : sim::controller_fields())
           if (f.tunable()) names.push_back(f.name);
         const json pair = {
             {"type", "array"}, {"items", {{"type", "number"}}}, {"minItems", 2}, {"maxItems", 2}};
         return json{
             {"type", "object"},
             {"minProperties", 1},
             {"propertyNames", {{"enum", names}}},
             {"additionalProperties",
              {{"oneOf",
                json::array(
                    {pair,
                     {{"type", "object"},
                      {"properties", {{"bounds", pair}, {"scale", {{"enum", {"linear", "log"}}}}}},
                      {"required", {"bounds"}},
                      {"additionalProperties", false}}})}}},
             {"description",
              "controller field → [lower, upper] or {\"bounds\": [lower, upper], "
              "\"scale\": \"log\"}: the search box (a field of the job's "
              "controller type, not an integer one); log scale searches ln x"}};
       }});
  o->field({"algorithm", false,
            [](const json& aj, const std::string& path, T& t, Errors& e) {
              t.algorithm = parse_algorithm(aj, path, e);
              if (!t.algorithm) t.algorithm = TuningConfig::default_algorithm();  // reported
            },
            [](const T& t, const std::string& path, Errors& e) {
              append(e, t.algorithm->validate(path));
            },
            [](const T& t, json& out) { out["algorithm"] = t.algorithm->to_json(); },
            [] {
              json cases = json::array();
              for (const AlgorithmInfo& a : algorithms()) {
                json c = a.schema();
                // The loader takes an object without "type" for the default algorithm.
                if (a.type == TuningConfig::default_algorithm()->type() && c.contains("required"))
                  c["required"].erase(
                      std::remove(c["required"].begin(), c["required"].end(), json("type")),
                      c["required"].end());
                cases.push_back(std::move(c));
              }
              return json{{"type", "object"},
                          {"oneOf", cases},
                          {"description",
                           "the optimiser and its settings; default the Bat "
                           "algorithm with the paper's Table 1 settings"}};
            }});
  o->uint64("seed", &T::seed, "seed of the optimiser's random numbers");
  o->choice("noise_floor", &T::noise_floor,
            {{"every_point", FrontNoiseFloor::every_point}, {"picked", FrontNoiseFloor::picked}},
            "a front's noise floor (8 nudged reruns on every scenario): at every point of the "
            "front, or at the picked point only (a job of one objective measures it at its "
            "tuned gains either way)",
            schema::kUnwrittenAtDefault);
  return o;
}

Ptr<TuningConfig> tuning_shape() {
  static const Ptr<TuningConfig> shape = make_tuning_shape();
  return shape;
}

// --- comparison entries -----------------------------------------------------------------------

// A controller object with an optional "label".
class CompareShape final : public schema::Shape<CompareEntry> {
 public:
  void read(const json& j, const std::string& path, CompareEntry& out,
            Errors& errs) const override {
    json body = j;
    if (j.is_object() && j.contains("label")) {
      if (!j["label"].is_string())
        errs.push_back(
            {path + "/label", "expected a string, got " + json_io::json_type_name(j["label"])});
      else
        out.label = j["label"].get<std::string>();
      body.erase("label");
    }
    runtime::controller_shape()->read(body, path, out.controller, errs);
    if (out.label.empty()) out.label = sim::to_string(out.controller.type);
  }
  void validate(const CompareEntry& c, const std::string& path, Errors& errs) const override {
    runtime::controller_shape()->validate(c.controller, path, errs);
  }
  json write(const CompareEntry& c) const override {
    json j = runtime::controller_shape()->write(c.controller);
    j["label"] = c.label;
    return j;
  }
  json json_schema() const override {
    json s = runtime::controller_shape()->json_schema();
    for (json& c : s["oneOf"])
      c["properties"]["label"] = {{"type", "string"},
                                  {"description", "shown in comparisons; default the type"}};
    s["description"] = "A controller simulated beside the job's own in comparisons and reports";
    return s;
  }
};

// --- the job ----------------------------------------------------------------------------------

// A member's scaled values are the base's times a factor from each scale's range, so the ends of
// the ranges give every value's extremes: the base scaled by each end of each scale must be a
// valid scenario, or some member would not be (an amplitude of 1e300 scaled by 1e10 is inf).
void validate_scale_ends(const Job& job, const sim::PlantKind& kind, Errors& errs) {
  const EnsembleConfig& e = *job.ensemble;
  const std::string& base_name =
      e.base.empty() && !job.scenarios.empty() ? job.scenarios.front().name : e.base;
  const auto base = std::find_if(job.scenarios.begin(), job.scenarios.end(),
                                 [&](const sim::Scenario& s) { return s.name == base_name; });
  if (base == job.scenarios.end() ||
      !base->validate("", kind.axes, kind.actuators_of(job.plant.values)).empty())
    return;  // its own errors say what is wrong
  const std::vector<double> ones(std::max<std::size_t>(6, base->initial_state.size()), 1.0);
  // Each scale: a parameter's (empty for the others), its key and its distribution.
  std::vector<std::tuple<std::string, std::string, const Distribution*>> scales;
  for (const ParameterScale& p : e.parameter_scales)
    if (kind.find_uncertain(p.parameter))  // else validate_ensemble's error
      scales.emplace_back(p.parameter, p.parameter + "_scale", &p.distribution);
  if (e.initial_state_scale)
    scales.emplace_back("", "initial_state_scale", &*e.initial_state_scale);
  if (e.disturbance_scale) scales.emplace_back("", "disturbance_scale", &*e.disturbance_scale);
  for (const auto& [parameter, name, scale] : scales) {
    for (const double f : {scale->a, scale->b}) {
      ParameterFactors parameter_factors;
      std::vector<double> state = ones;
      double disturbance = 1.0;
      if (!parameter.empty()) parameter_factors.push_back({parameter, {f, f, f}});
      if (name == "initial_state_scale") state.assign(state.size(), f);
      if (name == "disturbance_scale") disturbance = f;
      const sim::Scenario m = scaled_base(job, parameter_factors, state, disturbance);
      Errors wrong = m.validate("", kind.axes, kind.actuators_of(job.plant.values));
      append(wrong, kind.check_true_values(job.plant.values, m.true_values, ""));
      if (!wrong.empty()) {
        errs.push_back({"/ensemble/" + std::string(name),
                        "a member scaled by " + json_io::number_text(f) + " would have " +
                            wrong.front().path + " " + wrong.front().message});
        break;
      }
    }
  }
  // The per-actuator draws at their ends, on every actuator at once.
  const auto m = static_cast<std::size_t>(kind.actuators_of(job.plant.values));
  for (const auto& [name, d] : {std::pair{"actuator_scale", &e.actuator_scale},
                                std::pair{"actuator_misalignment", &e.actuator_misalignment}}) {
    if (!*d || !kind.find_uncertain(name)) continue;
    const bool scale = std::string_view(name) == "actuator_scale";
    if (scale && !((*d)->a > 0)) continue;  // the distribution's own error (a scale is > 0)
    for (const double f : {(*d)->a, (*d)->b}) {
      sim::Scenario s = scaled_base(job, {}, ones, 1.0);
      apply_actuator_draws(job, s, std::vector<double>(scale ? m : 0, f),
                           std::vector<double>(scale ? 0 : m, f));
      const Errors wrong = kind.check_true_values(job.plant.values, s.true_values, "");
      if (!wrong.empty()) {
        errs.push_back({"/ensemble/" + std::string(name),
                        "a member drawing " + json_io::number_text(f) + " would have " +
                            wrong.front().path + " " + wrong.front().message});
        break;
      }
    }
  }
}

// The ensemble against the job: its base, the plant's actuators and inertia, member names.
void validate_ensemble(const Job& job, const sim::PlantKind& kind, Errors& errs) {
  const EnsembleConfig& e = *job.ensemble;
  if (!e.base.empty() && std::none_of(job.scenarios.begin(), job.scenarios.end(),
                                      [&](const sim::Scenario& s) { return s.name == e.base; }))
    errs.push_back({"/ensemble/base", "no scenario is named \"" + e.base + "\" (known: " + [&] {
                      std::string n;
                      for (const sim::Scenario& s : job.scenarios)
                        n += (n.empty() ? "" : ", ") + s.name;
                      return n;
                    }() + ")"});
  for (const ParameterScale& p : e.parameter_scales)
    if (!kind.find_uncertain(p.parameter))
      errs.push_back({"/ensemble/" + p.parameter + "_scale",
                      kind.uncertain.empty()
                          ? "the " + kind.model + " plant declares no uncertain parameters to scale"
                          : "the " + kind.model + " plant does not declare " + p.parameter +
                                " uncertain (its uncertain parameters: " + kind.uncertain_names() +
                                ")"});
  for (const auto& [parameter, d] : {std::pair{"actuator_scale", &e.actuator_scale},
                                     std::pair{"actuator_misalignment", &e.actuator_misalignment}})
    if (*d && !kind.find_uncertain(parameter))
      errs.push_back({"/ensemble/" + std::string(parameter),
                      "the " + kind.model + " plant does not declare " + parameter +
                          " uncertain (its uncertain parameters: " + kind.uncertain_names() +
                          "; rigid_body has actuator_scale and actuator_misalignment, "
                          "multirotor actuator_scale)"});
  if (e.faults) {
    const FaultDistribution& f = *e.faults;
    const int actuators = kind.actuators_of(job.plant.values);
    std::set<int> seen;
    for (std::size_t i = 0; i < f.actuators.size(); ++i) {
      const int a = f.actuators[i];
      const std::string p = "/ensemble/faults/actuators/" + std::to_string(i);
      if (a < 1 || a > actuators)
        errs.push_back({p, "actuator " + std::to_string(a) + " does not exist: the " + kind.model +
                               " has actuators 1.." + std::to_string(actuators)});
      else if (!seen.insert(a).second)
        errs.push_back({p, "actuator " + std::to_string(a) + " is listed twice"});
    }
    const int listed = f.actuators.empty() ? actuators : static_cast<int>(f.actuators.size());
    if (f.count_hi > listed && f.count_lo >= 0 && f.count_hi >= f.count_lo)
      errs.push_back({"/ensemble/faults/count", "upper bound " + std::to_string(f.count_hi) +
                                                    " exceeds the " + std::to_string(listed) +
                                                    " listed actuators"});
  }
  if (!job.scenarios.empty()) {
    std::vector<FieldError> clashes = member_name_errors(job, e.count);
    errs.insert(errs.end(), clashes.begin(), clashes.end());
  }
  validate_scale_ends(job, kind, errs);
}

}  // namespace

std::vector<FieldError> member_name_errors(const Job& job, std::int64_t count) {
  // Member k is named <base>-k; none may take another scenario's name.
  std::vector<FieldError> errs;
  if (!job.ensemble || job.scenarios.empty()) return errs;
  const std::string& base =
      job.ensemble->base.empty() ? job.scenarios.front().name : job.ensemble->base;
  // Nor be longer than a scenario name may be (the members are written as scenarios).
  const std::string longest = base + "-" + std::to_string(std::max<std::int64_t>(count, 1) - 1);
  const bool base_exists = std::any_of(job.scenarios.begin(), job.scenarios.end(),
                                       [&](const sim::Scenario& s) { return s.name == base; });
  if (base_exists && safe_name(base) && !safe_name(longest))
    errs.push_back({job.ensemble->base.empty() ? "/scenarios/0/name" : "/ensemble/base",
                    "member names such as \"" + longest + "\" would be longer than " +
                        std::to_string(kMaxNameLength) +
                        " characters: shorten the base scenario's name"});
  for (std::size_t i = 0; i < job.scenarios.size(); ++i) {
    const std::string& n = job.scenarios[i].name;
    if (n.size() > base.size() + 1 && n.compare(0, base.size() + 1, base + "-") == 0) {
      const std::string k = n.substr(base.size() + 1);
      if (std::all_of(k.begin(), k.end(), ::isdigit) && (k == "0" || k[0] != '0') && k.size() < 8 &&
          std::stoll(k) < count)
        errs.push_back({"/scenarios/" + std::to_string(i) + "/name",
                        "\"" + n + "\" is also the name of ensemble member " + k});
    }
  }
  return errs;
}

namespace {

// Whether [t0, t1) holds a sample time k·Ts, 0 <= k < samples(), as the metrics count them.
bool holds_a_sample(const sim::Window& w, const sim::Scenario& s) {
  const double ts = s.sample_time;
  const std::int64_t n = s.samples();
  if (!(w.t0 < w.t1) || n <= 0) return false;
  double first = std::max(0.0, std::ceil(w.t0 / ts));
  if (!(first < static_cast<double>(n))) return false;
  auto k = static_cast<std::int64_t>(first);
  while (k > 0 && static_cast<double>(k - 1) * ts >= w.t0) --k;  // k·Ts as the loop rounds it
  while (k < n && static_cast<double>(k) * ts < w.t0) ++k;
  return k < n && static_cast<double>(k) * ts < w.t1;
}

// A window against the job's scenarios: its start >= 0, its end after its start and, measured
// from each run's start, not after any scenario's end; it holds a sample of every listed
// scenario (from its first fault when the window is) and of every ensemble member.
void check_window(const Job& job, const sim::Window& w, WindowFrom from, const std::string& path,
                  Errors& errs) {
  if (!std::isfinite(w.t0) || w.t0 < 0)
    errs.push_back({path + "/0", "must be >= 0 (got " + json_io::number_text(w.t0) + ")"});
  else if (!(w.t1 > w.t0))
    errs.push_back({path, "end " + json_io::number_text(w.t1) + " must be after start " +
                              json_io::number_text(w.t0)});
  else if (std::isfinite(w.t1) && from == WindowFrom::start)
    for (const sim::Scenario& s : job.scenarios)
      if (std::isfinite(s.duration) && w.t1 > s.duration + 1e-12) {
        errs.push_back({path + "/1", "end " + json_io::number_text(w.t1) +
                                         " is after the end of scenario \"" + s.name + "\" (" +
                                         json_io::number_text(s.duration) + " s)"});
        return;
      }
  if (!errs.empty() && errs.back().path.rfind(path, 0) == 0) return;
  // A window without a sample measures nothing: every candidate would score 0 (a blind search,
  // whose gains the loader then refuses), and in an ensemble such a member would count as 0.
  const auto empty_in = [&](const sim::Scenario& s, double onset) {
    sim::Window at = w;
    at.t0 += onset;
    at.t1 = std::min(at.t1 + onset, s.duration);
    return !holds_a_sample(at, s);
  };
  const auto first_onset = [](const sim::Scenario& s) {
    double first = std::numeric_limits<double>::infinity();
    for (const sim::Fault& f : s.faults) first = std::min(first, f.onset);
    return first;
  };
  const auto where = [&](const sim::Scenario& s) {
    return " (samples at k·" + json_io::number_text(s.sample_time) + " s before its end at " +
           json_io::number_text(s.duration) + " s)";
  };
  for (const sim::Scenario& s : job.scenarios) {
    if (!(s.sample_time > 0) || !std::isfinite(s.duration)) continue;  // reported elsewhere
    const bool from_fault = from == WindowFrom::first_fault && !s.faults.empty();
    const double onset = from_fault ? first_onset(s) : 0.0;
    if (empty_in(s, onset)) {
      errs.push_back({path, "holds no sample of scenario \"" + s.name + "\"" +
                                (from_fault ? " counted from its first fault at " +
                                                  json_io::number_text(onset) + " s"
                                            : std::string()) +
                                where(s)});
      return;
    }
  }
  // Ensemble members draw their faults: the window must hold a sample after the latest first
  // fault the draws can give (the onset's upper end, or half the duration when not drawn).
  if (job.ensemble && job.ensemble->faults && from == WindowFrom::first_fault &&
      job.ensemble->faults->count_hi > 0) {
    const sim::Scenario* base = job.scenarios.empty() ? nullptr : &job.scenarios.front();
    if (!job.ensemble->base.empty()) {
      base = nullptr;  // a base no scenario names is reported at /ensemble/base
      for (const sim::Scenario& s : job.scenarios)
        if (s.name == job.ensemble->base) base = &s;
    }
    if (!base || !(base->sample_time > 0) || !std::isfinite(base->duration)) return;
    const std::optional<Distribution>& onset = job.ensemble->faults->onset;
    const double latest = onset ? std::max(onset->a, onset->b) : 0.5 * base->duration;
    if (empty_in(*base, latest))
      errs.push_back({path, "holds no sample of an ensemble member whose first fault is at " +
                                json_io::number_text(latest) +
                                " s, the latest ensemble.faults.onset draws" + where(*base) +
                                ": shorten the window's start or the onsets"});
  }
}

// Every scenario with sensors, and the ensemble's members when they draw theirs, with its JSON
// path: the acceleration paths a tuned controller reads.
std::vector<std::pair<std::string, sim::AccelerationSensor>> acceleration_paths(const Job& job) {
  std::vector<std::pair<std::string, sim::AccelerationSensor>> paths;
  // A block whose measurements are exact is no sensors (Scenario::active_sensors): its loop is
  // the one without, whatever its acceleration says.
  for (std::size_t i = 0; i < job.scenarios.size(); ++i)
    if (const sim::SensorModel* m = job.scenarios[i].active_sensors())
      paths.emplace_back("/scenarios/" + std::to_string(i) + "/sensors/acceleration",
                         m->acceleration);
  if (job.ensemble && job.ensemble->sensors) {
    // Members copy their base's block (listed above when it reads sensors) or draw noise on
    // exact sensors, whose acceleration is the ideal one.
    const sim::Scenario* base = find_ensemble_base(job);
    if (base && !base->active_sensors())
      paths.emplace_back("/ensemble/sensors",
                         base->sensors ? base->sensors->acceleration : sim::AccelerationSensor{});
  }
  return paths;
}

std::string acceleration_text(const sim::AccelerationSensor& a) {
  if (a.source == sim::AccelerationSource::ideal) return "ideal";
  return "differentiated (time_constant " + json_io::number_text(a.time_constant) + " s)";
}

// A gains file records one acceleration path for flight software, so a tuned job's scenarios
// with sensors read the same one.
void validate_acceleration(const Job& job, Errors& errs) {
  const auto paths = acceleration_paths(job);
  for (std::size_t k = 1; k < paths.size(); ++k) {
    const sim::AccelerationSensor &a = paths[k].second, &first = paths[0].second;
    if (a.source == first.source &&
        (a.source == sim::AccelerationSource::ideal || a.time_constant == first.time_constant))
      continue;
    errs.push_back({paths[k].first, "is " + acceleration_text(a) + " but " + paths[0].first +
                                        " is " + acceleration_text(first) +
                                        ": the scenarios of a tuned job read one acceleration "
                                        "path, the one its gains file records for flight "
                                        "software"});
  }
}

// pagmo's multi-objective algorithms search fronts only: a job of one objective (or of one soft
// goal) cannot run them.
void validate_front_only(const Job& job, Errors& errs) {
  if (!job.tuning || !job.tuning->algorithm || job.tuning->algorithm->type() != "pagmo") return;
  const auto soft = std::count_if(job.goals.begin(), job.goals.end(),
                                  [](const GoalConfig& g) { return g.soft(); });
  if (soft >= 2) {
    append(errs, job.tuning->algorithm->validate_front(static_cast<std::size_t>(soft),
                                                       "/tuning/algorithm"));
    return;
  }
  const std::string name = job.tuning->algorithm->to_json().value("name", "");
  if (const PagmoAlgorithmInfo* info = find_pagmo_algorithm(name); info && info->front)
    errs.push_back({"/tuning/algorithm/name",
                    "pagmo's " + name +
                        " searches a Pareto front: give the job two or more soft "
                        "goals (\"minimize\": true), or name an algorithm of one objective"});
}

// The goals against the job: a soft goal among them, windows inside the scenarios, the settling
// threshold and tail their metrics need, no goal twice. One soft goal is the search's objective,
// so its metric is one that can be (MetricField::objective); two or more ask for a Pareto front
// (any metric), which the algorithm must search for.
void validate_goals(const Job& job, Errors& errs) {
  if (job.goals.empty()) return;
  bool soft = false;
  const auto soft_goals = std::count_if(job.goals.begin(), job.goals.end(),
                                        [](const GoalConfig& g) { return g.soft(); });
  if (soft_goals == 1)
    for (std::size_t i = 0; i < job.goals.size(); ++i)
      if (job.goals[i].soft() && !job.goals[i].metric->objective)
        errs.push_back({"/goals/" + std::to_string(i) + "/metric",
                        "a single soft goal is the search's objective: " + objective_metrics() +
                            " (got " + std::string(job.goals[i].metric->name) +
                            "; make it a limit with at_most, or add a second soft goal for a "
                            "Pareto front)"});
  if (soft_goals >= 2 && job.tuning && job.tuning->algorithm &&
      !job.tuning->algorithm->searches_front())
    errs.push_back({"/tuning/algorithm/type",
                    std::to_string(soft_goals) +
                        " soft goals (\"minimize\": true) ask for a "
                        "Pareto front, which algorithm " +
                        job.tuning->algorithm->type() +
                        " does not search for (bat and random do); or keep one soft goal and make "
                        "the others limits (\"at_most\")"});
  // Whether any run of the job can have a fault: a listed scenario with one, or ensemble
  // members that draw some.
  const bool faults =
      std::any_of(job.scenarios.begin(), job.scenarios.end(),
                  [](const sim::Scenario& s) { return !s.faults.empty(); }) ||
      (job.ensemble && job.ensemble->faults && job.ensemble->faults->count_hi > 0);
  std::vector<json> seen;
  for (std::size_t i = 0; i < job.goals.size(); ++i) {
    const GoalConfig& g = job.goals[i];
    const std::string p = "/goals/" + std::to_string(i);
    soft = soft || g.soft();
    // Measured from the first fault (settling_time) or per fault: undefined on every run of a
    // job without faults, so every candidate would score NaN and the front would be empty.
    if (!faults && (g.metric->per_fault || g.metric->setting == sim::MetricSetting::settling_threshold))
      errs.push_back({p + "/metric", std::string(g.metric->name) +
                                         " is measured after a fault, and no scenario of the job "
                                         "has one: give a scenario faults, or goal another metric"});
    if (g.windowed()) check_window(job, g.window, g.window_from, p + "/window", errs);
    // The setting the goal's metric is measured against: its own or the job's, not both apart.
    for (const SettingKeys& k : kSettingKeys) {
      if (g.metric->setting != k.setting) continue;
      const std::optional<double>& own = g.*k.own;
      const std::optional<double> from_job =
          job.metrics ? (*job.metrics).*k.from_job : std::optional<double>{};
      if (!own && !from_job)
        errs.push_back({p + "/" + k.key, std::string(g.metric->name) + " needs a " + k.key +
                                             ": give it here or as /metrics/" + k.job_key});
      else if (own && from_job && *own != *from_job)
        errs.push_back({p + "/" + k.key, json_io::number_text(*own) + " differs from /metrics/" +
                                             k.job_key + " " + json_io::number_text(*from_job) +
                                             " (a run measures one; give it in one place)"});
    }
    // A run measures one threshold and one tail: two goals may not ask for different ones.
    const auto agrees = [&](const std::optional<double>& own, const char* key,
                            std::optional<double> GoalConfig::*member) {
      if (!own) return;
      for (std::size_t k = 0; k < i; ++k)
        if (const std::optional<double>& other = job.goals[k].*member; other && *other != *own) {
          errs.push_back({p + "/" + key, json_io::number_text(*own) + " differs from /goals/" +
                                             std::to_string(k) + "/" + key + " " +
                                             json_io::number_text(*other) +
                                             " (a run measures one; give it in one place)"});
          return;
        }
    };
    agrees(g.threshold, "threshold", &GoalConfig::threshold);
    agrees(g.tail, "tail", &GoalConfig::tail);
    json canonical = goal_shape()->write(g);
    for (std::size_t k = 0; k < seen.size(); ++k)
      if (seen[k] == canonical) {
        errs.push_back({p, "is the same goal as /goals/" + std::to_string(k)});
        break;
      }
    seen.push_back(std::move(canonical));
  }
  if (!soft)
    errs.push_back({"/goals",
                    "needs one goal with \"minimize\": true (the search's objective); "
                    "every goal here is a limit"});
}

// The checks that span the job's parts: names, the scenarios against the plant's shape, the
// objective window against the scenarios, the tuned parameters against the controller.
void validate_job(const Job& job, Errors& errs) {
  if (!safe_name(job.name))
    errs.push_back({"/name",
                    "must be 1-100 characters of letters, digits, '_', '-', '.' "
                    "(it names the output directory); got \"" +
                        job.name + "\""});
  const sim::PlantKind* kind = sim::find_plant_kind(job.plant.model);
  const int n = kind ? kind->axes : sim::kMaxAxes,
            m = kind ? kind->actuators_of(job.plant.values) : sim::kMaxActuators;

  if (job.scenarios.empty()) errs.push_back({"/scenarios", "must hold at least one scenario"});
  std::set<std::string> names;
  for (std::size_t i = 0; i < job.scenarios.size(); ++i) {
    const sim::Scenario& s = job.scenarios[i];
    const std::string p = "/scenarios/" + std::to_string(i);
    Errors scenario_errors = s.validate(p, n, m);
    // An unknown plant (reported at /plant/model) has no shape to check the state's length by.
    if (!kind)
      std::erase_if(scenario_errors,
                    [&](const FieldError& e) { return e.path == p + "/initial_state"; });
    append(errs, std::move(scenario_errors));
    if (!s.name.empty() && !safe_name(s.name))
      errs.push_back(
          {p + "/name", "must be letters, digits, '_', '-', '.' (got \"" + s.name + "\")"});
    if (!names.insert(s.name).second)
      errs.push_back({p + "/name", "duplicate scenario name \"" + s.name + "\""});
  }

  if (job.goals.empty())
    check_window(job, job.objective.window, job.objective.window_from, "/objective/window", errs);
  validate_goals(job, errs);
  validate_front_only(job, errs);

  // A scenario's true values replace the plant's values of the uncertain parameters they name.
  for (std::size_t i = 0; kind && i < job.scenarios.size(); ++i) {
    const sim::Scenario& s = job.scenarios[i];
    if (s.true_values.empty()) continue;
    append(errs, kind->check_true_values(job.plant.values, s.true_values,
                                         "/scenarios/" + std::to_string(i)));
  }
  if (job.ensemble && kind) validate_ensemble(job, *kind, errs);

  if (!job.tuning) return;
  // A gains file is valid for one sample time, so every tuned scenario must share it.
  for (std::size_t i = 1; i < job.scenarios.size(); ++i)
    if (job.scenarios[i].sample_time != job.scenarios[0].sample_time)
      errs.push_back({"/scenarios/" + std::to_string(i) + "/sample_time",
                      "must equal the first scenario's sample_time " +
                          json_io::number_text(job.scenarios[0].sample_time) +
                          " when the job is tuned"});
  validate_acceleration(job, errs);
  if (job.tuning->parameters.empty())
    errs.push_back({"/tuning/parameters", "must name at least one controller parameter"});
  for (const ParameterBounds& b : job.tuning->parameters) {
    const std::string p = "/tuning/parameters/" + json_io::pointer_escape(b.name);
    const sim::ControllerField* f = sim::find_controller_field(b.name);
    if (!f || !f->applies_to(job.controller.type)) {
      std::string tunable;
      std::vector<std::string> tunable_names;
      for (const sim::ControllerField& g : sim::controller_fields())
        if (g.applies_to(job.controller.type) && g.tunable()) {
          tunable += (tunable.empty() ? "" : ", ") + std::string(g.name);
          tunable_names.emplace_back(g.name);
        }
      errs.push_back({p, "is not a parameter of controller " +
                             std::string(sim::to_string(job.controller.type)) + " (tunable: " +
                             tunable + ")" + json_io::did_you_mean(b.name, tunable_names)});
      continue;
    }
    if (!f->tunable()) {
      errs.push_back({p, "is an integer parameter and cannot be tuned"});
      continue;
    }
    if (!std::isfinite(b.lower) || !std::isfinite(b.upper)) {
      errs.push_back({p, "bounds must be finite numbers"});
      continue;
    }
    if (b.lower >= b.upper) {
      errs.push_back({p, "lower bound " + json_io::number_text(b.lower) + " is " +
                             (b.lower == b.upper ? "equal to" : "above") + " upper bound " +
                             json_io::number_text(b.upper)});
      continue;
    }
    // A log scale is only written {"bounds": [...], "scale": "log"}; the pair is nested there.
    const std::string bounds = b.scale == Scale::log ? p + "/bounds" : p;
    if (b.scale == Scale::log && !(b.lower > 0))
      errs.push_back({bounds + "/0",
                      "must be > 0 on a log scale (got " + json_io::number_text(b.lower) + ")"});
    for (int k = 0; k < 2; ++k) {
      const double v = k == 0 ? b.lower : b.upper;
      const std::string msg = sim::check_controller_value(job.controller, *f, v);
      if (!msg.empty())
        errs.push_back({bounds + "/" + std::to_string(k), std::string(k == 0 ? "lower" : "upper") +
                                                              " bound " + json_io::number_text(v) +
                                                              " is outside the valid range of " +
                                                              b.name + ": " + msg});
    }
  }
}

std::shared_ptr<const Obj<Job>> make_job_shape() {
  auto o = std::make_shared<Obj<Job>>(
      "A tuning job: the plant, fault scenarios, the controller, the objective and what to tune");
  o->field({"schema", true,
            [](const json& v, const std::string& path, Job&, Errors& e) {
              if (!v.is_string())
                e.push_back({path, "expected a string, got " + json_io::json_type_name(v)});
              else if (v.get<std::string>() != kJobSchema)
                e.push_back({path, "must be \"" + std::string(kJobSchema) + "\" (got \"" +
                                       v.get<std::string>() + "\")"});
            },
            [](const Job&, const std::string&, Errors&) {},
            [](const Job&, json& out) { out["schema"] = kJobSchema; },
            [] {
              return json{{"const", kJobSchema}};
            }});
  o->string("name", &Job::name, "names the output directory: letters, digits, '_', '-', '.'",
            kRequired, {}, kNamePattern);
  o->object("plant", &Job::plant, runtime::plant_shape(), "");
  o->array("scenarios", &Job::scenarios, scenario_shape(), "at least one", kRequired);
  o->object("controller", &Job::controller, runtime::controller_shape(),
            "the controller to tune, with its starting (baseline) values", kRequired);
  o->array("compare", &Job::compare, Ptr<CompareEntry>(std::make_shared<CompareShape>()),
           "controllers shown beside the job's own in comparisons", schema::kOptional, false);
  o->field({"objective", false,
            [](const json& v, const std::string& path, Job& job, Errors& e) {
              objective_shape()->read(v, path, job.objective, e);
            },
            [](const Job& job, const std::string& path, Errors& e) {
              if (job.goals.empty()) objective_shape()->validate(job.objective, path, e);
            },
            [](const Job& job, json& out) {  // a job with goals is scored by them
              if (job.goals.empty()) out["objective"] = objective_shape()->write(job.objective);
            },
            [] {
              json s = objective_shape()->json_schema();
              s["description"] = "What a candidate is scored by (default: " +
                                 std::string(ObjectiveConfig{}.metric->name) +
                                 " over the whole run, mean); a job gives objective or goals, "
                                 "not both";
              return s;
            }});
  o->array("goals", &Job::goals, goal_shape(),
           "soft goals (minimize) and hard goals (at_most) in place of the objective: one soft "
           "goal and any hard ones make a constrained search",
           schema::kOptional, false);
  o->optional_object("metrics", &Job::metrics, metrics_shape(), "");
  o->optional_object("tuning", &Job::tuning, tuning_shape(), "");
  o->field({"ensemble", false,
            [](const json& v, const std::string& path, Job& job, Errors& e) {
              auto config = std::make_shared<EnsembleConfig>();
              job_detail::ensemble_shape()->read(v, path, *config, e);
              job.ensemble = std::move(config);
            },
            [](const Job& job, const std::string& path, Errors& e) {
              if (job.ensemble) job_detail::ensemble_shape()->validate(*job.ensemble, path, e);
            },
            [](const Job& job, json& out) {
              if (job.ensemble)
                out["ensemble"] = job_detail::ensemble_shape()->write(*job.ensemble);
            },
            [] { return job_detail::ensemble_shape()->json_schema(); }});
  o->rule([](const Job& job, const std::string&, Errors& e) { validate_job(job, e); });
  return o;
}

const Obj<Job>& job_shape() {
  static const std::shared_ptr<const Obj<Job>> shape = make_job_shape();
  return *shape;
}

}  // namespace

// --- public ----------------------------------------------------------------------------------

const char* to_string(Aggregate a) {
  switch (a) {
    case Aggregate::mean:
      return "mean";
    case Aggregate::max:
      return "max";
    case Aggregate::quantile:
      return "quantile";
    case Aggregate::cvar:
      return "cvar";
  }
  return "?";
}

ObjectiveConfig GoalConfig::measure() const {
  ObjectiveConfig o;
  o.window = window;
  o.window_from = window_from;
  o.aggregate = aggregate;
  o.q = q;
  o.alpha = alpha;
  return o;
}

double GoalConfig::violation(double value) const {
  if (!at_most) return 0.0;
  if (!(value <= std::numeric_limits<double>::max()))
    return std::numeric_limits<double>::infinity();
  return std::max(0.0, value / *at_most - 1.0);
}

sim::Window ObjectiveConfig::window_of(const sim::Scenario& s) const {
  sim::Window w = window;
  if (window_from == WindowFrom::first_fault && !s.faults.empty()) {
    double first = s.faults.front().onset;
    for (const sim::Fault& f : s.faults) first = std::min(first, f.onset);
    w.t0 += first;
    w.t1 += first;
  }
  w.t1 = std::min(w.t1, s.duration);  // cut at the end of the run
  return w;
}

double ObjectiveConfig::aggregate_of(std::vector<double> v) const {
  if (v.empty()) return 0.0;
  if (aggregate == Aggregate::mean) {
    double sum = 0.0;  // in scenario order
    for (double x : v) sum += x;
    return sum / static_cast<double>(v.size());
  }
  if (aggregate == Aggregate::max) return *std::max_element(v.begin(), v.end());
  std::sort(v.begin(), v.end());  // a NaN never comes: a diverged run is +inf
  const double n = static_cast<double>(v.size());
  if (aggregate == Aggregate::quantile) {
    const auto rank = static_cast<std::size_t>(std::ceil(q * n));  // nearest rank, 1-based
    return v[std::clamp<std::size_t>(rank, 1, v.size()) - 1];
  }
  const auto k =
      std::clamp<std::size_t>(static_cast<std::size_t>(std::ceil((1.0 - alpha) * n)), 1, v.size());
  double sum = 0.0;  // the k largest, ascending
  for (std::size_t i = v.size() - k; i < v.size(); ++i) sum += v[i];
  return sum / static_cast<double>(k);
}

AlgorithmPtr TuningConfig::default_algorithm() {
  static const AlgorithmPtr bat = make_algorithm({{"type", "bat"}});
  return bat;
}

std::vector<FieldError> Job::validate() const {
  Errors errs;
  job_shape().validate(*this, "", errs);
  return errs;
}

std::int64_t Job::steps_per_evaluation() const {
  std::int64_t n = 0;
  for (const sim::Scenario& s : scenarios) n += s.samples() * s.substeps;
  if (ensemble) {  // members copy the base's duration, sample time and substeps
    const sim::Scenario& base = ensemble_base(*this);
    n += ensemble->count * base.samples() * base.substeps;
  }
  return n;
}

double Job::step_cost_per_evaluation() const {
  const auto cost = [](const sim::Scenario& s, std::size_t faults) {
    return static_cast<double>(s.samples()) * static_cast<double>(s.substeps) *
           (1.0 + static_cast<double>(faults) * kFaultStepCost);
  };
  double n = 0.0;
  for (const sim::Scenario& s : scenarios) n += cost(s, s.faults.size());
  if (ensemble) {
    const sim::Scenario& base = ensemble_base(*this);
    const std::size_t faults = ensemble->faults
                                   ? static_cast<std::size_t>(std::max(ensemble->faults->count_hi, 0))
                                   : base.faults.size();
    n += static_cast<double>(ensemble->count) * cost(base, faults);
  }
  return n;
}

std::size_t Job::scenario_count() const {
  return scenarios.size() + (ensemble ? static_cast<std::size_t>(ensemble->count) : 0);
}

bool Job::reads_sensors() const {
  return (ensemble && ensemble->sensors) ||
         std::any_of(scenarios.begin(), scenarios.end(),
                     [](const sim::Scenario& s) { return s.active_sensors() != nullptr; });
}

std::optional<sim::AccelerationSensor> Job::tuned_acceleration() const {
  const auto paths = acceleration_paths(*this);
  if (paths.empty()) return std::nullopt;
  return paths.front().second;
}

Job parse_job(const json& j_in, const std::string& source,
              const std::optional<std::filesystem::path>& base_dir) {
  Errors errs;
  json j = j_in;
  // "scenarios": {"file": ...} names an ftctune.scenarios/1 file (what `ftctune ensemble`
  // writes); its entries take the place of the list, and their stated recoverability is
  // checked against the plant below.
  std::vector<std::optional<bool>> stated;
  // The file's entries, read one by one as the file is parsed (the file's text and document are
  // never whole in memory), with the errors they hold: those count only once the file as a
  // whole proves to be a scenarios file, as if it were read first and its entries after.
  std::vector<sim::Scenario> listed;
  Errors entry_errs, flag_errs;
  bool from_file = false, file_failed = false;
  if (j.is_object() && j.contains("scenarios") && j["scenarios"].is_object()) {
    const json ref = j["scenarios"];
    j["scenarios"] = json::array();
    if (ref.size() != 1 || !ref.contains("file") || !ref["file"].is_string()) {
      errs.push_back({"/scenarios", "expected an array of scenarios or {\"file\": path}"});
    } else if (!base_dir) {
      errs.push_back({"/scenarios/file",
                      "scenario files are read relative to a job file; this "
                      "job has none (give the scenarios inline)"});
    } else {
      const std::filesystem::path file = *base_dir / ref["file"].get<std::string>();
      const auto entry = [&](std::size_t i, json&& e) {
        std::optional<bool> r;
        if (e.is_object() && e.contains("recoverable")) {
          if (e["recoverable"].is_boolean())
            r = e["recoverable"].get<bool>();
          else
            flag_errs.push_back({"/scenarios/file", file.string() + ": /scenarios/" +
                                                        std::to_string(i) +
                                                        "/recoverable must be true or false"});
          e.erase("recoverable");
        }
        stated.push_back(r);
        listed.emplace_back();
        scenario_shape()->read(e, "/scenarios/" + std::to_string(i), listed.back(), entry_errs);
      };
      std::optional<json> doc;
      try {
        doc = json_io::parse_json_file(file, file.string(), "scenarios", entry);
        if (!doc) errs.push_back({"/scenarios/file", "cannot open " + file.string()});
      } catch (const InputError& e) {
        if (e.source() != file.string()) throw;  // not the file's reading: the entry's own
        errs.push_back({"/scenarios/file", e.what()});
      }
      if (doc) {
        if (!doc->is_object())
          errs.push_back({"/scenarios/file", file.string() + " is not a JSON object"});
        else if (!doc->contains("schema") || !(*doc)["schema"].is_string() ||
                 (*doc)["schema"].get<std::string>() != kScenariosSchema)
          errs.push_back(
              {"/scenarios/file",
               file.string() + " is " +
                   (doc->contains("schema") ? (*doc)["schema"].dump() : std::string("unnamed")) +
                   ", not a scenarios file (" + kScenariosSchema + ")"});
        else if (!doc->contains("scenarios") || !(*doc)["scenarios"].is_array())
          errs.push_back({"/scenarios/file", file.string() + " lists no scenarios"});
        else
          from_file = true;
      }
    }
    if (from_file) {
      errs.insert(errs.end(), flag_errs.begin(), flag_errs.end());
    } else {
      stated.clear();
      listed = {};
      entry_errs.clear();
    }
    file_failed = !errs.empty();
  }
  // A job gives objective or goals; with goals its objective is the soft goal's measure (when
  // that is an error integral), which is what the runs score by.
  const bool has_goals = j.is_object() && j.contains("goals");
  if (has_goals && j.contains("objective"))
    errs.push_back({"/goals",
                    "a job gives \"objective\" or \"goals\", not both (the objective "
                    "is a single soft goal)"});
  if (has_goals && j["goals"].is_array() && j["goals"].empty())
    errs.push_back({"/goals", "must hold at least one goal"});
  Job job;
  const std::size_t read_from = errs.size();
  job_shape().read(j, "", job, errs);
  j = json();  // the job holds what it read
  if (from_file) {
    job.scenarios = std::move(listed);
    // The entries' errors where reading them in the job would have put them: after those of
    // the fields the job's shape reads before "scenarios" (read() reports in its fields' order).
    const std::size_t scenarios_at = job_shape().field_index("scenarios");
    const auto before_scenarios = [&](const FieldError& e) {
      if (e.path.size() < 2) return false;  // the job as a whole
      const std::size_t end = e.path.find('/', 1);
      const std::string key = e.path.substr(1, end == std::string::npos ? end : end - 1);
      return job_shape().field_index(key) < scenarios_at;
    };
    auto at = errs.begin() + static_cast<std::ptrdiff_t>(read_from);
    while (at != errs.end() && before_scenarios(*at)) ++at;
    errs.insert(at, entry_errs.begin(), entry_errs.end());
  }
  for (const GoalConfig& g : job.goals)
    if (g.soft() && g.metric->objective) {
      job.objective = g.measure();
      job.objective.metric = g.metric;
      break;
    }
  // Every default filled in: the plant's parameters, and a scenario without an initial state
  // starts from its plant's default one.
  if (const sim::PlantKind* kind = sim::find_plant_kind(job.plant.model)) {
    if (job.plant.values.empty()) job.plant.values = kind->defaults();
    for (sim::Scenario& s : job.scenarios)
      if (s.initial_state.empty()) s.initial_state = kind->default_initial_state;
  }
  // Each listed scenario's sensor noise stream (SPEC §18): its seed (default 1) and its index
  // (default its place in the list).
  for (std::size_t i = 0; i < job.scenarios.size(); ++i)
    if (std::optional<sim::SensorModel>& m = job.scenarios[i].sensors) m->resolve(1, i);
  Errors range;
  job_shape().validate(job, "", range);
  // Without its scenarios file the job has no scenarios: say why once, not what follows from it.
  if (file_failed)
    std::erase_if(range, [](const FieldError& e) {
      return e.path == "/scenarios" || e.path == "/ensemble/base";
    });
  schema::detail::dedupe_append(errs, std::move(range));
  if (errs.empty() && !stated.empty()) {
    const std::unique_ptr<sim::AnyPlant> plant = sim::make_plant(job.plant);
    for (std::size_t i = 0; i < stated.size() && i < job.scenarios.size(); ++i)
      if (stated[i] && *stated[i] != plant->recoverable(job.scenarios[i]))
        errs.push_back({"/scenarios/" + std::to_string(i) + "/recoverable",
                        std::string("the scenarios file says ") + (*stated[i] ? "true" : "false") +
                            ", but its faults leave the plant " +
                            (*stated[i] ? "without" : "with") + " full control"});
  }
  throw_if_errors(source, std::move(errs));
  return job;
}

Job parse_job_text(const std::string& text, const std::string& source,
                   const std::optional<std::filesystem::path>& base_dir) {
  return parse_job(json_io::parse_json_text(text, source), source, base_dir);
}

Job load_job(const std::filesystem::path& file) {
  const std::optional<std::string> text = read_file(file);
  if (!text) throw InputError(file.string(), "", "cannot open the job file");
  return parse_job_text(*text, file.string(), file.parent_path());
}

json job_json_schema() {
  json body = job_shape().json_schema();
  // The scenarios may also come from a scenarios file (parse_job reads it before the shape does).
  json listed = body["properties"]["scenarios"];
  const std::string doc = listed.value("description", "");
  listed.erase("description");
  body["properties"]["scenarios"] = {
      {"description", doc + "; or {\"file\": path} naming an " + kScenariosSchema +
                          " file, relative to the job file"},
      {"anyOf",
       {listed,
        {{"type", "object"},
         {"properties", {{"file", {{"type", "string"}, {"minLength", 1}}}}},
         {"required", {"file"}},
         {"additionalProperties", false}}}}};
  return schema::document(body, "https://ftctune.example/schemas/ftctune.job-1.json",
                          "ftctune job file (ftctune.job/1)");
}

// --- JSON output -----------------------------------------------------------------------------

json to_json(const Job& job) { return job_shape().write(job); }
json to_json(const PlantConfig& p) { return runtime::plant_shape()->write(p); }
json to_json(const ObjectiveConfig& o) { return objective_shape()->write(o); }
json to_json(const GoalConfig& g) { return goal_shape()->write(g); }

}  // namespace ftc::tune
