#include "ftc/runtime/controller_json.hpp"

#include <cmath>
#include <nlohmann/json.hpp>

#include "ftc/runtime/json_reader.hpp"

namespace ftc::runtime {

using nlohmann::json;
using sim::ControllerConfig;
using sim::ControllerField;
using sim::ControllerType;

namespace {

std::string field_doc(const ControllerField& f, ControllerType t) {
  std::string d = f.description;
  if (*f.unit_for(t)) d += " (" + std::string(f.unit_for(t)) + ")";
  if (*f.rule) d += "; " + std::string(f.rule);
  return d;
}

// One table field of a controller: a number, or an integer held in a double (p, q, nodes).
schema::Object<ControllerConfig>::Field table_field(const ControllerField& f, ControllerType t) {
  const ControllerConfig dflt;
  return {f.name, false,
          [&f](const json& v, const std::string& path, ControllerConfig& c, schema::Errors& e) {
            double d = 0;
            if (!schema::detail::read_number(v, path, d, e)) return;
            if (f.integer && d != std::floor(d)) {
              e.push_back({path, "expected an integer, got " + json_io::number_text(d)});
              return;
            }
            c.*f.member = d;
          },
          // Ranges and the rules between fields are ControllerConfig::validate's (the
          // variant's rule below), so that a config built in code is checked the same way.
          [](const ControllerConfig&, const std::string&, schema::Errors&) {},
          [&f](const ControllerConfig& c, json& o) {
            double v = c.*f.member;
            if (f.optional && std::isnan(v)) v = c.resolved_alpha1();
            if (f.integer)
              o[f.name] = static_cast<long long>(v);
            else
              o[f.name] = v;
          },
          [&f, t, dflt] {
            json s = {{"type", f.integer ? "integer" : "number"},
                      {"description", field_doc(f, t)}};
            schema::annotate(f.range, s);
            const double d = dflt.*f.member;
            if (std::isfinite(d)) s["default"] = d;
            return s;
          }};
}

// A controller's line of the table (controllers.hpp) in words, for its case of the schema.
std::string case_description(const sim::ControllerInfo& c) {
  std::string d = std::string(c.display_name) + ": " + c.description;
  d += c.model_based ? "; uses the plant model f(X)" : "; learns f(X)";
  if (c.integral) d += "; integral state";
  if (c.adaptive) d += "; adaptive switching gain";
  return d;
}

std::shared_ptr<const schema::Variant<ControllerConfig>> make_shape() {
  auto v = std::make_shared<schema::Variant<ControllerConfig>>(
      "type", [](const ControllerConfig& c) { return std::string(sim::to_string(c.type)); },
      [](ControllerConfig& c, const std::string& name) {
        // A new type starts from its Table 1 values.
        c = ControllerConfig::table1(*sim::controller_type_from_string(name));
      },
      "A sliding-mode controller: its type and parameters (Table 1 values by default)", "",
      [](const std::string& name) {
        std::vector<std::string> names;
        for (const sim::ControllerInfo& c : sim::kControllers) names.emplace_back(c.name);
        return "unknown controller type \"" + name + "\" (known: " +
               std::string(sim::controller_type_list()) + ")" +
               json_io::did_you_mean(name, names);
      });
  for (const sim::ControllerInfo& info : sim::kControllers) {
    const ControllerType t = info.type;
    auto o = std::make_shared<schema::Object<ControllerConfig>>(case_description(info));
    for (const ControllerField& f : sim::controller_fields())
      if (f.applies_to(t)) o->field(table_field(f, t));
    if (info.adaptive)
      o->numbers("centre_range", &ControllerConfig::centre_range, 2, schema::Range::any(),
                 "[lower, upper] of the node centres on the diagonal");
    const std::string name = sim::to_string(t);
    o->unknown_key_message([name, t](const std::string& key) {
      const ControllerField* f = sim::find_controller_field(key);
      if ((f && !f->applies_to(t)) || key == "centre_range")
        return "does not apply to controller type " + name;
      std::string allowed;
      for (const std::string& n : sim::controller_field_names(t)) allowed += ", " + n;
      return "unknown key (allowed here: type" + allowed + ")" +
             json_io::did_you_mean(key, sim::controller_field_names(t));
    });
    o->rule([](const ControllerConfig& c, const std::string& path, schema::Errors& e) {
      for (FieldError& err : c.validate(path)) e.push_back(std::move(err));
    });
    v->add(name, std::move(o));
  }
  return v;
}

}  // namespace

std::shared_ptr<const schema::Shape<ControllerConfig>> controller_shape() {
  static const std::shared_ptr<const schema::Variant<ControllerConfig>> shape = make_shape();
  return shape;
}

ControllerConfig parse_controller(const json& j, const std::string& path,
                                  std::vector<FieldError>& errs) {
  ControllerConfig c;
  controller_shape()->read(j, path, c, errs);
  return c;
}

json to_json(const ControllerConfig& c) { return controller_shape()->write(c); }

}  // namespace ftc::runtime
