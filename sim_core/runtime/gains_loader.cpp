#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "ftc/runtime/gains.hpp"
#include "ftc/runtime/controller_json.hpp"
#include "ftc/runtime/json_reader.hpp"

namespace ftc::runtime {

using nlohmann::json;
using json_io::ObjectReader;

namespace {

void require_kind(ObjectReader& r, const char* key, bool (json::*is)() const noexcept,
                  const char* kind, std::vector<FieldError>& errs) {
  if (const json* v = r.child(key, true); v && !((*v).*is)())
    errs.push_back({r.path(key),
                    std::string("expected ") + kind + ", got " + json_io::json_type_name(*v)});
}

}  // namespace

Gains parse_gains(const json& doc, const std::string& source) {
  std::vector<FieldError> errs;
  Gains g;
  ObjectReader r(doc, "", errs);
  if (!r.ok()) throw InputError(source, std::move(errs));

  std::string schema;
  if (!r.string("schema", schema, true)) throw InputError(source, std::move(errs));
  if (schema != kGainsSchema)
    throw InputError(source, "/schema",
                     "this file is \"" + schema + "\", expected \"" + kGainsSchema + "\"");

  if (const json* c = r.child("controller", true)) {
    g.controller = parse_controller(*c, "/controller", errs);
    std::vector<FieldError> v = g.controller.validate("/controller");
    errs.insert(errs.end(), v.begin(), v.end());
  }
  if (const json* t = r.child("tuned", true)) {
    if (!t->is_object()) {
      errs.push_back({"/tuned", "expected an object of name: value"});
    } else {
      for (auto it = t->begin(); it != t->end(); ++it) {
        const std::string p = "/tuned/" + json_io::pointer_escape(it.key());
        const sim::ControllerField* f = sim::find_controller_field(it.key());
        if (!it.value().is_number()) {
          errs.push_back({p, "expected a number"});
        } else if (!f || !f->applies_to(g.controller.type)) {
          errs.push_back({p, "is not a parameter of the controller"});
        } else {
          const double v = it.value().get<double>();
          g.tuned.emplace_back(it.key(), v);
          const double in_controller = g.controller.*f->member;
          if (in_controller != v)
            errs.push_back({p, "value " + json_io::number_text(v, 17) +
                                   " differs from /controller/" + it.key() + " = " +
                                   json_io::number_text(in_controller, 17)});
        }
      }
    }
  }
  if (r.number("sample_time", g.sample_time, true) &&
      !(g.sample_time > 0 && std::isfinite(g.sample_time)))
    errs.push_back({"/sample_time", "must be > 0"});
  require_kind(r, "plant", &json::is_object, "an object", errs);
  require_kind(r, "objective", &json::is_object, "an object", errs);
  if (const json* f = r.child("fitness", true); f && !(f->is_number() || f->is_null()))
    errs.push_back({"/fitness", "expected a number or null"});
  require_kind(r, "baseline", &json::is_object, "an object", errs);
  require_kind(r, "optimizer", &json::is_object, "an object", errs);
  require_kind(r, "history", &json::is_array, "an array", errs);
  if (const json* j = r.child("job", true)) {
    ObjectReader jr(*j, "/job", errs);
    jr.string("name", g.job_name, true);
    jr.string("sha256", g.job_sha256, true);
    jr.finish();
  }
  require_kind(r, "generator", &json::is_object, "an object", errs);
  r.finish();
  throw_if_errors(source, std::move(errs));
  return g;
}

Gains read_gains(const std::filesystem::path& file) {
  const std::optional<std::string> text = json_io::read_file(file);
  if (!text) throw InputError(file.string(), "", "cannot open the gains file");
  return parse_gains(json_io::parse_json_text(*text, file.string()), file.string());
}

void check_sample_time(const Gains& gains, double sample_time) {
  if (!(std::abs(sample_time - gains.sample_time) <= 1e-12 * gains.sample_time))
    throw InputError("gains", "/sample_time",
                     "the gains were tuned for Ts = " + json_io::number_text(gains.sample_time, 17) +
                         " s, but the controller is to run at Ts = " +
                         json_io::number_text(sample_time, 17) + " s");
}

}  // namespace ftc::runtime
