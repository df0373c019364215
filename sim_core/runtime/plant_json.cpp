#include "ftc/runtime/plant_json.hpp"

#include <nlohmann/json.hpp>

#include "ftc/runtime/json_reader.hpp"
#include "vehicle_json.hpp"

namespace ftc::runtime {

using nlohmann::json;
using schema::Errors;

namespace {

template <class T>
using Ptr = std::shared_ptr<const schema::Shape<T>>;

// One parameter of a plant kind: a number or an array, stored in PlantSpec::values at `offset`.
schema::Object<sim::PlantSpec>::Field plant_field(const sim::PlantParameter& p, std::size_t offset,
                                                  const std::vector<double>& defaults) {
  const std::string doc = p.description + (p.unit.empty() ? "" : " (" + p.unit + ")");
  return {p.name,
          false,
          [n = p.size(), offset, name = p.name](const json& v, const std::string& path,
                                                sim::PlantSpec& out, Errors& e) {
            if (n == 1) {
              schema::detail::read_number(v, path, out.values[offset], e);
              return;
            }
            if (!v.is_array() || v.size() != n) {
              e.push_back({path, "expected an array of " + std::to_string(n) + " numbers, got " +
                                     (v.is_array() ? "an array of " + std::to_string(v.size())
                                                   : json_io::json_type_name(v))});
              return;
            }
            for (std::size_t i = 0; i < n; ++i) {
              if (name == "inertia" && v[i].is_array()) {
                e.push_back({path,
                             "this plant takes the 3 principal moments [Ix, Iy, Iz] only; "
                             "for a full inertia tensor use the rigid_body or multirotor "
                             "plant"});
                return;
              }
              schema::detail::read_number(v[i], path + "/" + std::to_string(i),
                                          out.values[offset + i], e);
            }
          },
          [](const sim::PlantSpec&, const std::string&, Errors&) {},  // the kind's rule checks
          [name = p.name, n = p.size(), offset, defaults](const sim::PlantSpec& c, json& o) {
            const std::vector<double>& v =
                c.values.empty() ? defaults : c.values;  // unset: defaults
            if (n == 1)
              o[name] = v.at(offset);
            else
              o[name] = std::vector<double>(v.begin() + offset, v.begin() + offset + n);
          },
          [doc, p] {
            json item = schema::detail::number_schema("", p.range);
            if (p.size() == 1) {
              item["description"] = doc;
              item["default"] = p.defaults[0];
              return item;
            }
            return json{{"type", "array"},      {"items", item},         {"minItems", p.size()},
                        {"maxItems", p.size()}, {"default", p.defaults}, {"description", doc}};
          }};
}

Ptr<sim::PlantSpec> make_plant_shape() {
  auto v = std::make_shared<schema::Variant<sim::PlantSpec>>(
      "model", [](const sim::PlantSpec& p) { return p.model; },
      [](sim::PlantSpec& p, const std::string& model) {
        p.model = model;
        p.values = sim::find_plant_kind(model)->defaults();
      },
      "The plant: its model and parameters (every parameter has a default)", "spacecraft",
      [](const std::string& model) {
        return "unknown plant model '" + model + "' (known: " + sim::plant_model_names() + ")";
      });
  for (const sim::PlantKind& k : sim::plant_kinds()) {
    std::shared_ptr<schema::Object<sim::PlantSpec>> o = detail::structured_plant_object(k);
    if (o) {
      o->rule([&k](const sim::PlantSpec& c, const std::string& path, Errors& e) {
        if (c.values.empty()) return;
        for (FieldError& err : k.validate(c.values, path)) e.push_back(std::move(err));
      });
      v->add(k.model, std::move(o));
      continue;
    }
    o = std::make_shared<schema::Object<sim::PlantSpec>>(k.description);
    std::size_t offset = 0;
    for (const sim::PlantParameter& p : k.parameters) {
      o->field(plant_field(p, offset, k.defaults()));
      offset += p.size();
    }
    o->rule([&k](const sim::PlantSpec& c, const std::string& path, Errors& e) {
      if (c.values.empty()) return;  // the defaults
      for (FieldError& err : k.validate(c.values, path)) e.push_back(std::move(err));
    });
    v->add(k.model, std::move(o));
  }
  return v;
}

Ptr<sim::PlantSpec> cached_plant_shape() {
  static const Ptr<sim::PlantSpec> shape = make_plant_shape();
  return shape;
}

}  // namespace

std::shared_ptr<const schema::Shape<sim::PlantSpec>> plant_shape() { return cached_plant_shape(); }

}  // namespace ftc::runtime
