#include <cmath>
#include <nlohmann/json.hpp>

#include "ftc/runtime/controller_json.hpp"
#include "ftc/runtime/gains.hpp"
#include "ftc/runtime/json_reader.hpp"
#include "ftc/runtime/plant_json.hpp"
#include "ftc/runtime/scenario_json.hpp"
#include "ftc/runtime/schema.hpp"

namespace ftc::runtime {

using nlohmann::json;
using schema::Errors;
using schema::kRequired;

namespace {

// The parts of a gains file the runtime does not use (the objective, the baseline, the
// optimiser and its history) are checked for their kind only: they document the run.
schema::Object<Gains>::Field informational(const char* key, const char* kind, const char* doc,
                                           bool required = true) {
  const bool array = std::string_view(kind) == "array";
  return {key,
          required,
          [array](const json& v, const std::string& path, Gains&, Errors& e) {
            if (array ? !v.is_array() : !v.is_object())
              e.push_back({path, std::string("expected ") + (array ? "an array" : "an object") +
                                     ", got " + json_io::json_type_name(v)});
          },
          [](const Gains&, const std::string&, Errors&) {},
          [](const Gains&, json&) {},
          [kind, doc] {
            return json{{"type", kind}, {"description", doc}};
          }};
}

struct JobRef {
  std::string name, sha256;
};

std::shared_ptr<const schema::Object<Gains>> make_gains_shape() {
  auto o = std::make_shared<schema::Object<Gains>>(
      "A gains file: the tuned controller and what it was tuned for");
  o->field({"schema", true, [](const json&, const std::string&, Gains&, Errors&) {},  // read first
            [](const Gains&, const std::string&, Errors&) {}, [](const Gains&, json&) {},
            [] {
              return json{{"const", kGainsSchema}};
            }});
  o->object("controller", &Gains::controller, controller_shape(),
            "the controller with every parameter, the tuned ones included", kRequired);
  o->field({"tuned", true,
            [](const json& t, const std::string& path, Gains& g, Errors& e) {
              if (!t.is_object()) {
                e.push_back({path, "expected an object of name: value"});
                return;
              }
              for (auto it = t.begin(); it != t.end(); ++it) {
                const std::string p = path + "/" + json_io::pointer_escape(it.key());
                if (!it.value().is_number())
                  e.push_back({p, "expected a number"});
                else
                  g.tuned.emplace_back(it.key(), it.value().get<double>());
              }
            },
            // Each tuned value is a parameter of the controller and equals it there.
            [](const Gains& g, const std::string& path, Errors& e) {
              for (const auto& [name, v] : g.tuned) {
                const std::string p = path + "/" + json_io::pointer_escape(name);
                const sim::ControllerField* f = sim::find_controller_field(name);
                if (!f || !f->applies_to(g.controller.type)) {
                  e.push_back({p, "is not a parameter of the controller"});
                  continue;
                }
                const double in_controller = g.controller.*f->member;
                if (in_controller != v)
                  e.push_back({p, "value " + json_io::number_text(v, 17) +
                                      " differs from /controller/" + name + " = " +
                                      json_io::number_text(in_controller, 17)});
              }
            },
            [](const Gains&, json&) {},
            [] {
              return json{{"type", "object"},
                          {"additionalProperties", {{"type", "number"}}},
                          {"description", "tuned parameter → value (also in controller)"}};
            }});
  o->number("sample_time", &Gains::sample_time, schema::Range::positive(),
            "the sample time Ts the gains were tuned for (s)", kRequired);
  o->object("plant", &Gains::plant, plant_shape(), "the plant as simulated", kRequired);
  o->optional_object("acceleration", &Gains::acceleration, acceleration_shape(),
                     "the acceleration the controller read in tuning, written when the job's "
                     "scenarios have sensors: ideal, or the measured rates differentiated "
                     "through a low-pass of time constant τ (s), which flight software must "
                     "reproduce (ftc/runtime/acceleration.hpp); absent: the exact acceleration");
  o->field(informational("objective", "object", "metric, window, aggregate and the value reached"));
  o->field(informational("goals", "object",
                         "a job with goals: each goal with the value reached, the total "
                         "violation of the hard goals, feasible, and the rule that chose",
                         false));
  o->field({"fitness", true,
            [](const json& v, const std::string& path, Gains& g, Errors& e) {
              if (v.is_number())
                g.fitness = v.get<double>();
              else if (!v.is_null())
                e.push_back({path, "expected a number or null"});
            },
            // The format records a failed tuning; the loader refuses to deploy one.
            [](const Gains& g, const std::string& path, Errors& e) {
              if (!g.fitness)
                e.push_back({path,
                             "is null: every candidate diverged in tuning, so these gains "
                             "must not be deployed"});
              else if (!(*g.fitness > 0) || !std::isfinite(*g.fitness))
                e.push_back({path, "is " + json_io::number_text(*g.fitness) +
                                       ": every candidate diverged in tuning, or none met "
                                       "the job's hard goals (a usable controller has a "
                                       "fitness > 0), so these gains must not be deployed"});
            },
            [](const Gains&, json&) {},
            [] {
              return json{{"type", json::array({"number", "null"})},
                          {"description",
                           "J = 1/objective of the tuned controller; 0 or null when every "
                           "candidate diverged, in [-1, 0) when none met the job's hard goals "
                           "(-V/(1 + V), V the total violation); the loader refuses both"}};
            }});
  o->field(informational("baseline", "object", "the job's own controller and its score"));
  // The optimiser's record, read for one flag: gains of a run stopped before its last
  // iteration are the best of a partial search, not the tuning's answer.
  {
    schema::Object<Gains>::Field f =
        informational("optimizer", "object", "algorithm, settings, seed, evaluations, completed");
    const auto kind = f.read;
    f.read = [kind](const json& v, const std::string& path, Gains& g, Errors& e) {
      kind(v, path, g, e);
      if (v.is_object() && v.contains("completed") && v["completed"] != json(true))
        e.push_back({path + "/completed",
                     "is " + v["completed"].dump() +
                         ": the tuning was stopped before its last iteration, so these are the "
                         "best gains of a partial search and must not be deployed"});
    };
    o->field(std::move(f));
  }
  o->field(informational("history", "array", "one row per iteration"));
  o->field({"job", true,
            [](const json& v, const std::string& path, Gains& g, Errors& e) {
              static const schema::Object<JobRef> ref =
                  schema::Object<JobRef>()
                      .string("name", &JobRef::name, "job name", kRequired)
                      .string("sha256", &JobRef::sha256, "of the job's canonical JSON", kRequired);
              JobRef r;
              ref.read(v, path, r, e);
              g.job_name = r.name;
              g.job_sha256 = r.sha256;
            },
            [](const Gains&, const std::string&, Errors&) {}, [](const Gains&, json&) {},
            [] {
              return json{{"type", "object"},
                          {"required", {"name", "sha256"}},
                          {"additionalProperties", false},
                          {"properties",
                           {{"name", {{"type", "string"}}},
                            {"sha256", {{"type", "string"}, {"pattern", "^[0-9a-f]{64}$"}}}}}};
            }});
  o->field(informational("generator", "object", "the tool and version that wrote the file"));
  o->field(informational("warnings", "array",
                         "sentences about the result a user should act on, e.g. a tuned value at "
                         "a bound of its search range",
                         false));
  o->field(informational("noise_floor", "object",
                         "the tuned objective re-evaluated with the initial state nudged by a "
                         "relative 1e-12 (perturbation, repeats, objective_min, objective_max, "
                         "relative_spread) and, with sensors, with other sensor seeds "
                         "(sensor_seeds, rounding_spread, sensor_spread)",
                         false));
  return o;
}

const schema::Object<Gains>& gains_shape() {
  static const std::shared_ptr<const schema::Object<Gains>> shape = make_gains_shape();
  return *shape;
}

}  // namespace

Gains parse_gains(const json& doc, const std::string& source) {
  if (!doc.is_object())
    throw InputError(source, "", "expected an object, got " + json_io::json_type_name(doc));
  // The schema first: a file of another kind gets one clear line, not a list of its fields.
  const auto s = doc.find("schema");
  if (s == doc.end()) throw InputError(source, "/schema", "is required");
  if (!s->is_string() || s->get<std::string>() != kGainsSchema)
    throw InputError(
        source, "/schema",
        "this file is " +
            (s->is_string() ? "\"" + s->get<std::string>() + "\"" : json_io::json_type_name(*s)) +
            ", expected \"" + kGainsSchema + "\"");
  Errors errs;
  Gains g;
  schema::read(gains_shape(), doc, "", g, errs);
  throw_if_errors(source, std::move(errs));
  return g;
}

Gains read_gains(const std::filesystem::path& file) {
  const std::optional<std::string> text = json_io::read_file(file);
  if (!text) throw InputError(file.string(), "", "cannot open the gains file");
  return parse_gains(json_io::parse_json_text(*text, file.string()), file.string());
}

json gains_json_schema() {
  return schema::document(gains_shape().json_schema(),
                          "https://ftctune.example/schemas/ftctune.gains-1.json",
                          "ftctune gains file (ftctune.gains/1)");
}

void check_job(const Gains& gains, const std::string& job_sha256) {
  if (gains.job_sha256 != job_sha256)
    throw InputError("gains", "/job/sha256",
                     "the gains were tuned on job \"" + gains.job_name + "\" (SHA-256 " +
                         gains.job_sha256.substr(0, 12) + "…), not on this job (" +
                         job_sha256.substr(0, 12) + "…)");
}

void check_plant_model(const Gains& gains, const std::string& model) {
  if (gains.plant.model != model)
    throw InputError("gains", "/plant/model",
                     "the gains were tuned for a \"" + gains.plant.model +
                         "\" plant, but the controller is to run on a \"" + model + "\" plant");
}

void check_plant(const Gains& gains, const sim::PlantSpec& expected) {
  check_plant_model(gains, expected.model);
  const sim::PlantKind* kind = sim::find_plant_kind(expected.model);
  if (!kind) return;  // a model the loader would have refused: never the file's
  const std::vector<double> want = expected.values.empty() ? kind->defaults() : expected.values;
  const std::vector<double>& got = gains.plant.values;
  if (want.size() != kind->value_count() || got.size() != want.size())
    throw InputError("plant", "",
                     std::string("a ")
                         .append(expected.model)
                         .append(" plant has ")
                         .append(std::to_string(kind->value_count()))
                         .append(" parameter values, the expected plant gives ")
                         .append(std::to_string(want.size())));
  Errors errs;
  std::size_t offset = 0;
  for (const sim::PlantParameter& p : kind->parameters) {
    for (std::size_t i = 0; i < p.size(); ++i) {
      const std::size_t k = offset + i;
      if (std::abs(got[k] - want[k]) <= 1e-12 * std::abs(want[k])) continue;
      std::string path = "/plant/" + json_io::pointer_escape(p.name);
      if (p.size() > 1) path.append("/").append(std::to_string(i));
      errs.push_back({path, std::string("the gains were tuned for ")
                                .append(json_io::number_text(got[k], 17))
                                .append(", the plant has ")
                                .append(json_io::number_text(want[k], 17))});
    }
    offset += p.size();
  }
  throw_if_errors("gains", std::move(errs));
}

void check_sample_time(const Gains& gains, double sample_time) {
  if (!(std::abs(sample_time - gains.sample_time) <= 1e-12 * gains.sample_time))
    throw InputError(
        "gains", "/sample_time",
        "the gains were tuned for Ts = " + json_io::number_text(gains.sample_time, 17) +
            " s, but the controller is to run at Ts = " + json_io::number_text(sample_time, 17) +
            " s");
}

}  // namespace ftc::runtime
