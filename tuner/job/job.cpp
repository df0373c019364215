#include "ftc/tune/job/job.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>

#include "ftc/runtime/controller_json.hpp"
#include "ftc/tune/io/files.hpp"
#include "ftc/runtime/json_reader.hpp"

namespace ftc::tune {

using json_io::ObjectReader;
using nlohmann::json;

namespace {

void append(std::vector<FieldError>& to, std::vector<FieldError> from) {
  to.insert(to.end(), std::make_move_iterator(from.begin()), std::make_move_iterator(from.end()));
}

bool safe_name(const std::string& s) {
  if (s.empty() || s.size() > 100 || s[0] == '.') return false;
  for (char c : s)
    if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-' || c == '.'))
      return false;
  return true;
}

// --- parsing (structure and types) ---------------------------------------------------------

PlantConfig parse_plant(const json& j, const std::string& path, std::vector<FieldError>& errs) {
  PlantConfig p;
  ObjectReader r(j, path, errs);
  r.string("model", p.model);
  const sim::PlantKind* kind = sim::find_plant_kind(p.model);
  if (!kind) {
    errs.push_back({r.path("model"), "unknown plant model '" + p.model +
                                         "' (known: " + sim::plant_model_names() + ")"});
    return p;
  }
  p.values = kind->defaults();
  std::size_t offset = 0;
  for (const sim::PlantParameter& param : kind->parameters) {
    if (param.size() == 1)
      r.number(param.name.c_str(), p.values[offset]);
    else
      r.numbers(param.name.c_str(), p.values.data() + offset, param.size());
    offset += param.size();
  }
  r.finish();
  return p;
}

// The plant's kind, or the default spacecraft's when the model is unknown (already reported).
const sim::PlantKind& kind_of(const PlantConfig& p) {
  const sim::PlantKind* k = sim::find_plant_kind(p.model);
  return k ? *k : *sim::find_plant_kind("spacecraft");
}

sim::DisturbanceTerm parse_disturbance(const json& j, const std::string& path,
                                       std::vector<FieldError>& errs) {
  sim::DisturbanceTerm d;
  ObjectReader r(j, path, errs);
  r.integer("axis", d.axis, true);
  std::string shape = "sin";
  if (r.string("shape", shape)) {
    if (shape == "sin")
      d.shape = sim::Shape::sin;
    else if (shape == "cos")
      d.shape = sim::Shape::cos;
    else
      errs.push_back({r.path("shape"), "must be \"sin\" or \"cos\" (got \"" + shape + "\")"});
  }
  r.number("amplitude", d.amplitude, true);
  r.number("frequency", d.frequency, true);
  r.number("phase", d.phase);
  r.finish();
  return d;
}

sim::Fault parse_fault(const json& j, const std::string& path, std::vector<FieldError>& errs) {
  sim::Fault f;
  ObjectReader r(j, path, errs);
  if (!r.ok()) return f;
  r.integer("actuator", f.actuator, true);
  r.number("onset", f.onset, true);
  std::string type;
  if (r.string("type", type, true)) {
    if (type == "bias") {
      f.type = sim::FaultType::bias;
      r.number("offset", f.offset);
      r.number("amplitude", f.amplitude);
      r.number("frequency", f.frequency);
      r.number("phase", f.phase);
    } else if (type == "loss_of_effectiveness") {
      f.type = sim::FaultType::loss_of_effectiveness;
      r.number("fraction", f.fraction, true);
    } else if (type == "stuck") {
      f.type = sim::FaultType::stuck;
      r.number("value", f.value, true);
    } else {
      errs.push_back({r.path("type"),
                      "must be one of bias, loss_of_effectiveness, stuck (got \"" + type + "\")"});
      for (const std::string& k : r.keys()) r.mark_seen(k);  // no point listing them
    }
  }
  if (const json* pj = r.child("profile")) {
    ObjectReader pr(*pj, r.path("profile"), errs);
    std::string ptype = "abrupt";
    if (pr.string("type", ptype, true)) {
      if (ptype == "abrupt") {
        f.profile.type = sim::FaultProfileType::abrupt;
      } else if (ptype == "incipient") {
        f.profile.type = sim::FaultProfileType::incipient;
        pr.number("rate", f.profile.rate, true);
      } else {
        errs.push_back(
            {pr.path("type"), "must be \"abrupt\" or \"incipient\" (got \"" + ptype + "\")"});
      }
    }
    pr.finish();
  }
  r.finish();
  return f;
}

template <class T, class F>
std::vector<T> parse_array(const json* j, const std::string& path, std::vector<FieldError>& errs,
                           F&& parse_one) {
  std::vector<T> out;
  if (!j) return out;
  if (!j->is_array()) {
    errs.push_back({path, "expected an array, got " + json_io::json_type_name(*j)});
    return out;
  }
  for (std::size_t i = 0; i < j->size(); ++i)
    out.push_back(parse_one((*j)[i], path + "/" + std::to_string(i), errs));
  return out;
}

sim::Scenario parse_scenario(const json& j, const std::string& path,
                             std::vector<FieldError>& errs) {
  sim::Scenario s;
  ObjectReader r(j, path, errs);
  r.string("name", s.name, true);
  r.number("duration", s.duration, true);
  r.number("sample_time", s.sample_time);
  r.integer("substeps", s.substeps);
  s.initial_state.clear();  // absent: the plant's default, filled in by parse_job
  r.number_list("initial_state", s.initial_state);
  s.disturbance = parse_array<sim::DisturbanceTerm>(r.child("disturbance"), r.path("disturbance"),
                                                    errs, parse_disturbance);
  s.faults = parse_array<sim::Fault>(r.child("faults"), r.path("faults"), errs, parse_fault);
  double sat = 0;
  if (r.number("saturation", sat)) s.saturation = sat;
  r.finish();
  return s;
}

ObjectiveConfig parse_objective(const json& j, const std::string& path,
                                std::vector<FieldError>& errs) {
  ObjectiveConfig o;
  ObjectReader r(j, path, errs);
  std::string metric;
  if (r.string("metric", metric)) {
    if (auto m = sim::metric_from_string(metric))
      o.metric = *m;
    else
      errs.push_back({r.path("metric"), "must be one of ise, iae, itae (got \"" + metric + "\")"});
  }
  // [t0, t1] in s; t1 may be null, meaning "to the end of each scenario".
  if (const json* w = r.child("window")) {
    const std::string wp = r.path("window");
    if (!w->is_array() || w->size() != 2 || !(*w)[0].is_number() ||
        !((*w)[1].is_number() || (*w)[1].is_null()))
      errs.push_back({wp, "expected [start, end] in seconds, got " + json_io::json_type_name(*w)});
    else
      o.window = {(*w)[0].get<double>(), (*w)[1].is_null() ? std::numeric_limits<double>::infinity()
                                                           : (*w)[1].get<double>()};
  }
  std::string agg;
  if (r.string("aggregate", agg)) {
    if (agg == "mean")
      o.aggregate = Aggregate::mean;
    else if (agg == "max")
      o.aggregate = Aggregate::max;
    else
      errs.push_back({r.path("aggregate"), "must be \"mean\" or \"max\" (got \"" + agg + "\")"});
  }
  r.finish();
  return o;
}

TuningConfig parse_tuning(const json& j, const std::string& path, std::vector<FieldError>& errs) {
  TuningConfig t;
  ObjectReader r(j, path, errs);
  if (const json* pj = r.child("parameters", true)) {
    const std::string pp = r.path("parameters");
    if (!pj->is_object()) {
      errs.push_back(
          {pp, "expected an object of name: [lower, upper], got " + json_io::json_type_name(*pj)});
    } else {
      for (auto it = pj->begin(); it != pj->end(); ++it) {
        ParameterBounds b;
        b.name = it.key();
        const std::string bp = pp + "/" + json_io::pointer_escape(it.key());
        const json& v = it.value();
        if (!v.is_array() || v.size() != 2 || !v[0].is_number() || !v[1].is_number()) {
          errs.push_back({bp, "expected [lower, upper] (two numbers), got " +
                                  (v.is_array() ? "an array of " + std::to_string(v.size())
                                                : json_io::json_type_name(v))});
          continue;
        }
        b.lower = v[0].get<double>();
        b.upper = v[1].get<double>();
        t.parameters.push_back(b);
      }
      // JSON objects are unordered: fix the decision-vector order as that of the controller
      // field table (Kp before Ki), unknown names last, so it never depends on the file.
      const auto rank = [](const std::string& n) {
        const auto fields = sim::controller_fields();
        for (std::size_t i = 0; i < fields.size(); ++i)
          if (n == fields[i].name) return i;
        return fields.size();
      };
      std::stable_sort(t.parameters.begin(), t.parameters.end(),
                       [&](const ParameterBounds& a, const ParameterBounds& b) {
                         return rank(a.name) != rank(b.name) ? rank(a.name) < rank(b.name)
                                                             : a.name < b.name;
                       });
    }
  }
  if (const json* aj = r.child("algorithm")) {
    t.algorithm = parse_algorithm(*aj, r.path("algorithm"), errs);
    if (!t.algorithm) t.algorithm = TuningConfig::default_algorithm();  // reported
  }
  r.uint64("seed", t.seed);
  r.finish();
  return t;
}

// --- validation helpers ----------------------------------------------------------------------

void check_positive_int(std::vector<FieldError>& errs, const std::string& path, int v, int hi) {
  if (v < 1 || v > hi)
    errs.push_back({path, "must be an integer in 1.." + std::to_string(hi) + " (got " +
                              std::to_string(v) + ")"});
}

void check_unit(std::vector<FieldError>& errs, const std::string& path, double v, bool open_low) {
  const bool ok = std::isfinite(v) && (open_low ? v > 0 : v >= 0) && v <= 1;
  if (!ok)
    errs.push_back({path, std::string("must be in ") + (open_low ? "(0, 1]" : "[0, 1]") + " (got " +
                              json_io::number_text(v) + ")"});
}

}  // namespace

// --- public ----------------------------------------------------------------------------------

const char* to_string(Aggregate a) { return a == Aggregate::mean ? "mean" : "max"; }
AlgorithmPtr TuningConfig::default_algorithm() {
  static const AlgorithmPtr bat = make_algorithm({{"type", "bat"}});
  return bat;
}

std::vector<FieldError> Job::validate() const {
  std::vector<FieldError> errs;
  if (!safe_name(name))
    errs.push_back({"/name",
                    "must be 1-100 characters of letters, digits, '_', '-', '.' "
                    "(it names the output directory); got \"" +
                        name + "\""});
  const sim::PlantKind& kind = kind_of(plant);
  if (sim::find_plant_kind(plant.model)) append(errs, kind.validate(plant.values, "/plant"));

  if (scenarios.empty()) errs.push_back({"/scenarios", "must hold at least one scenario"});
  std::set<std::string> names;
  for (std::size_t i = 0; i < scenarios.size(); ++i) {
    const std::string p = "/scenarios/" + std::to_string(i);
    append(errs, scenarios[i].validate(p, kind.axes, kind.actuators));
    if (!scenarios[i].name.empty() && !safe_name(scenarios[i].name))
      errs.push_back({p + "/name", "must be letters, digits, '_', '-', '.' (got \"" +
                                       scenarios[i].name + "\")"});
    if (!names.insert(scenarios[i].name).second)
      errs.push_back({p + "/name", "duplicate scenario name \"" + scenarios[i].name + "\""});
  }

  append(errs, controller.validate("/controller"));
  for (std::size_t i = 0; i < compare.size(); ++i)
    append(errs, compare[i].controller.validate("/compare/" + std::to_string(i)));

  const sim::Window& w = objective.window;
  if (!std::isfinite(w.t0) || w.t0 < 0)
    errs.push_back({"/objective/window/0", "must be >= 0 (got " + json_io::number_text(w.t0) + ")"});
  else if (!(w.t1 > w.t0))
    errs.push_back({"/objective/window", "end " + json_io::number_text(w.t1) +
                                             " must be after start " + json_io::number_text(w.t0)});
  else if (std::isfinite(w.t1))
    for (const sim::Scenario& s : scenarios)
      if (std::isfinite(s.duration) && w.t1 > s.duration + 1e-12) {
        errs.push_back({"/objective/window/1",
                        "end " + json_io::number_text(w.t1) + " is after the end of scenario \"" +
                            s.name + "\" (" + json_io::number_text(s.duration) + " s)"});
        break;
      }

  if (tuning) {
    append(errs, tuning->algorithm->validate("/tuning/algorithm"));
    // A gains file is valid for one sample time, so every tuned scenario must share it.
    for (std::size_t i = 1; i < scenarios.size(); ++i)
      if (scenarios[i].sample_time != scenarios[0].sample_time)
        errs.push_back({"/scenarios/" + std::to_string(i) + "/sample_time",
                        "must equal the first scenario's sample_time " +
                            json_io::number_text(scenarios[0].sample_time) +
                            " when the job is tuned"});
    if (tuning->parameters.empty())
      errs.push_back({"/tuning/parameters", "must name at least one controller parameter"});
    for (const ParameterBounds& b : tuning->parameters) {
      const std::string p = "/tuning/parameters/" + json_io::pointer_escape(b.name);
      const sim::ControllerField* f = sim::find_controller_field(b.name);
      if (!f || !f->applies_to(controller.type)) {
        std::string tunable;
        for (const sim::ControllerField& g : sim::controller_fields())
          if (g.applies_to(controller.type) && g.tunable())
            tunable += (tunable.empty() ? "" : ", ") + std::string(g.name);
        errs.push_back({p, "is not a parameter of controller " +
                               std::string(sim::to_string(controller.type)) +
                               " (tunable: " + tunable + ")"});
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
      for (int k = 0; k < 2; ++k) {
        const double v = k == 0 ? b.lower : b.upper;
        const std::string msg = sim::check_controller_value(controller, *f, v);
        if (!msg.empty())
          errs.push_back({p + "/" + std::to_string(k), std::string(k == 0 ? "lower" : "upper") +
                                                           " bound " + json_io::number_text(v) +
                                                           " is outside the valid range of " +
                                                           b.name + ": " + msg});
      }
    }
  }
  return errs;
}

std::int64_t Job::steps_per_evaluation() const {
  std::int64_t n = 0;
  for (const sim::Scenario& s : scenarios) n += s.samples() * s.substeps;
  return n;
}

Job parse_job(const json& j, const std::string& source) {
  std::vector<FieldError> errs;
  Job job;
  ObjectReader r(j, "", errs);
  if (!r.ok()) throw InputError(source, std::move(errs));

  std::string schema;
  if (r.string("schema", schema, true) && schema != kJobSchema)
    errs.push_back(
        {"/schema", "must be \"" + std::string(kJobSchema) + "\" (got \"" + schema + "\")"});
  r.string("name", job.name, true);
  if (const json* p = r.child("plant"))
    job.plant = parse_plant(*p, "/plant", errs);
  else
    job.plant.values = kind_of(job.plant).defaults();
  job.scenarios =
      parse_array<sim::Scenario>(r.child("scenarios", true), "/scenarios", errs, parse_scenario);
  if (const json* c = r.child("controller", true))
    job.controller = parse_controller(*c, "/controller", errs);
  job.compare = parse_array<CompareEntry>(
      r.child("compare"), "/compare", errs,
      [](const json& cj, const std::string& p, std::vector<FieldError>& e) {
        CompareEntry entry;
        json body = cj;
        if (cj.is_object() && cj.contains("label")) {
          if (!cj["label"].is_string())
            e.push_back(
                {p + "/label", "expected a string, got " + json_io::json_type_name(cj["label"])});
          else
            entry.label = cj["label"].get<std::string>();
          body.erase("label");
        }
        entry.controller = parse_controller(body, p, e);
        if (entry.label.empty()) entry.label = sim::to_string(entry.controller.type);
        return entry;
      });
  if (const json* o = r.child("objective")) job.objective = parse_objective(*o, "/objective", errs);
  if (const json* t = r.child("tuning")) job.tuning = parse_tuning(*t, "/tuning", errs);
  r.finish();
  for (sim::Scenario& s : job.scenarios)
    if (s.initial_state.empty()) s.initial_state = kind_of(job.plant).default_initial_state;

  // Range checks only where parsing found nothing: a missing or mistyped field is reported once.
  for (FieldError& e : job.validate()) {
    bool known = false;
    for (const FieldError& p : errs) known = known || p.path == e.path;
    if (!known) errs.push_back(std::move(e));
  }
  throw_if_errors(source, std::move(errs));
  return job;
}

Job parse_job_text(const std::string& text, const std::string& source) {
  return parse_job(json_io::parse_json_text(text, source), source);
}

Job load_job(const std::filesystem::path& file) {
  const std::optional<std::string> text = read_file(file);
  if (!text) throw InputError(file.string(), "", "cannot open the job file");
  return parse_job_text(*text, file.string());
}

// --- JSON output -----------------------------------------------------------------------------

json to_json(const PlantConfig& p) {
  json j = {{"model", p.model}};
  std::size_t offset = 0;
  for (const sim::PlantParameter& param : kind_of(p).parameters) {
    if (param.size() == 1)
      j[param.name] = p.values.at(offset);
    else
      j[param.name] = std::vector<double>(p.values.begin() + offset,
                                          p.values.begin() + offset + param.size());
    offset += param.size();
  }
  return j;
}

json to_json(const ObjectiveConfig& o) {
  json w = json::array({o.window.t0});
  if (std::isfinite(o.window.t1))
    w.push_back(o.window.t1);
  else
    w.push_back(nullptr);
  return {
      {"metric", sim::to_string(o.metric)}, {"window", w}, {"aggregate", to_string(o.aggregate)}};
}

json to_json(const sim::Scenario& s) {
  json j;
  j["name"] = s.name;
  j["duration"] = s.duration;
  j["sample_time"] = s.sample_time;
  j["substeps"] = s.substeps;
  j["initial_state"] = s.initial_state;
  j["disturbance"] = json::array();
  for (const sim::DisturbanceTerm& d : s.disturbance)
    j["disturbance"].push_back({{"axis", d.axis},
                                {"shape", sim::to_string(d.shape)},
                                {"amplitude", d.amplitude},
                                {"frequency", d.frequency},
                                {"phase", d.phase}});
  j["faults"] = json::array();
  for (const sim::Fault& f : s.faults) {
    json fj = {{"actuator", f.actuator}, {"type", sim::to_string(f.type)}, {"onset", f.onset}};
    json prof = {{"type", sim::to_string(f.profile.type)}};
    if (f.profile.type == sim::FaultProfileType::incipient) prof["rate"] = f.profile.rate;
    fj["profile"] = prof;
    switch (f.type) {
      case sim::FaultType::bias:
        fj["offset"] = f.offset;
        fj["amplitude"] = f.amplitude;
        fj["frequency"] = f.frequency;
        fj["phase"] = f.phase;
        break;
      case sim::FaultType::loss_of_effectiveness:
        fj["fraction"] = f.fraction;
        break;
      case sim::FaultType::stuck:
        fj["value"] = f.value;
        break;
    }
    j["faults"].push_back(fj);
  }
  if (s.saturation) j["saturation"] = *s.saturation;
  return j;
}

json to_json(const Job& job) {
  json j;
  j["schema"] = kJobSchema;
  j["name"] = job.name;
  j["plant"] = to_json(job.plant);
  j["scenarios"] = json::array();
  for (const sim::Scenario& s : job.scenarios) j["scenarios"].push_back(to_json(s));
  j["controller"] = to_json(job.controller);
  if (!job.compare.empty()) {
    j["compare"] = json::array();
    for (const CompareEntry& c : job.compare) {
      json cj = to_json(c.controller);
      cj["label"] = c.label;
      j["compare"].push_back(cj);
    }
  }
  j["objective"] = to_json(job.objective);
  if (job.tuning) {
    const TuningConfig& t = *job.tuning;
    json params = json::object();
    for (const ParameterBounds& b : t.parameters) params[b.name] = {b.lower, b.upper};
    const json alg = t.algorithm->to_json();
    j["tuning"] = {{"parameters", params}, {"algorithm", alg}, {"seed", t.seed}};
  }
  return j;
}

}  // namespace ftc::tune
