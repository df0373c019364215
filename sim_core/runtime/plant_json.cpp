#include "ftc/runtime/plant_json.hpp"

#include <nlohmann/json.hpp>

#include "ftc/runtime/json_reader.hpp"
#include "ftc/sim/plant_plugin.hpp"
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
  for (const sim::PlantKind* kp : sim::all_plant_kinds()) {
    const sim::PlantKind& k = *kp;
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

// The plant's shape over the kinds a job can name now: the shipped ones and the plugins loaded so
// far (rebuilt when one is loaded). A job naming plugin:NAME loads it first (or gets, at /model,
// why it cannot); a model no kind has stays in `out`, so that the job's checks know the plant's
// shape is unknown and do not guess it.
class PlantShape final : public schema::Shape<sim::PlantSpec> {
 public:
  void read(const json& j, const std::string& path, sim::PlantSpec& out,
            Errors& errs) const override {
    std::string model;
    if (j.is_object())
      if (const auto it = j.find("model"); it != j.end() && it->is_string())
        model = it->get<std::string>();
    if (model.rfind(sim::kPluginPrefix, 0) == 0) try {
        sim::find_plant_plugin(model);
      } catch (const InputError& e) {
        errs.push_back({path + "/model", e.errors().front().message});
        out.model = model;
        out.values.clear();
        return;
      }
    shape_.read(j, path, out, errs);
    if (!model.empty() && !sim::find_plant_kind(model)) {
      out.model = model;
      out.values.clear();
    }
  }
  void validate(const sim::PlantSpec& value, const std::string& path, Errors& errs) const override {
    shape_.validate(value, path, errs);
  }
  json write(const sim::PlantSpec& value) const override { return shape_.write(value); }
  json json_schema() const override { return shape_.json_schema(); }

 private:
  schema::Regenerated<sim::PlantSpec> shape_{make_plant_shape, sim::plant_kinds_generation};
};

}  // namespace

std::shared_ptr<const schema::Shape<sim::PlantSpec>> plant_shape() {
  static const auto shape = std::make_shared<const PlantShape>();
  return shape;
}

}  // namespace ftc::runtime
