// The JSON of the rigid_body and multirotor plants (SPEC §17): a 3-list or 3×3 inertia, an
// `actuators` block (axes or a preset, limits) and a `rotors` list or preset, read into
// ftc/sim/vehicles.hpp's specs and stored flattened in PlantSpec::values.
#include "vehicle_json.hpp"

#include <algorithm>
#include <nlohmann/json.hpp>

#include "ftc/runtime/json_reader.hpp"
#include "ftc/sim/vehicles.hpp"

namespace ftc::runtime::detail {

using nlohmann::json;
using schema::Errors;

namespace {

bool read_num(const json& v, const std::string& path, double& out, Errors& e) {
  return schema::detail::read_number(v, path, out, e);
}

std::string names_of(const std::vector<std::string>& v) {
  std::string s;
  for (const std::string& n : v) s += (s.empty() ? "" : ", ") + n;
  return s;
}

// Keys of `v` outside `allowed`, each an error.
void unknown_keys(const json& v, const std::string& path, const std::vector<std::string>& allowed,
                  Errors& e) {
  for (const auto& [key, value] : v.items())
    if (std::find(allowed.begin(), allowed.end(), key) == allowed.end())
      e.push_back({path + "/" + key, "unknown key (allowed: " + names_of(allowed) + ")" +
                                         json_io::did_you_mean(key, allowed)});
}

bool read_inertia(const json& v, const std::string& path, std::array<double, 9>& J, Errors& e) {
  const auto is_row = [](const json& r) { return r.is_array(); };
  if (v.is_array() && v.size() == 3 && std::none_of(v.begin(), v.end(), is_row)) {
    std::array<double, 9> d{};
    bool ok = true;
    for (std::size_t i = 0; i < 3; ++i)
      ok = read_num(v[i], path + "/" + std::to_string(i), d[4 * i], e) && ok;
    if (ok) J = d;
    return ok;
  }
  if (v.is_array() && v.size() == 3 && std::all_of(v.begin(), v.end(), is_row)) {
    std::array<double, 9> d{};
    bool ok = true;
    for (std::size_t r = 0; r < 3; ++r) {
      const std::string rp = path + "/" + std::to_string(r);
      if (v[r].size() != 3) {
        e.push_back({rp, "expected a row of 3 numbers, got " + std::to_string(v[r].size())});
        ok = false;
        continue;
      }
      for (std::size_t c = 0; c < 3; ++c)
        ok = read_num(v[r][c], rp + "/" + std::to_string(c), d[3 * r + c], e) && ok;
    }
    if (ok) J = d;
    return ok;
  }
  e.push_back({path,
               "expected 3 principal moments [Ix, Iy, Iz] or a symmetric 3×3 tensor "
               "[[Ixx, Ixy, Ixz], [Ixy, Iyy, Iyz], [Ixz, Iyz, Izz]] in kg·m², got " +
                   (v.is_array() ? "an array of " + std::to_string(v.size())
                                 : json_io::json_type_name(v))});
  return false;
}

json write_inertia(const std::array<double, 9>& J) {
  if (J[1] == 0.0 && J[2] == 0.0 && J[5] == 0.0 && J[3] == 0.0 && J[6] == 0.0 && J[7] == 0.0)
    return json::array({J[0], J[4], J[8]});
  return json::array({json::array({J[0], J[1], J[2]}), json::array({J[3], J[4], J[5]}),
                      json::array({J[6], J[7], J[8]})});
}

json inertia_schema() {
  const json num = {{"type", "number"}};
  return {{"description",
           "the inertia tensor J in kg·m²: 3 principal moments, or the symmetric positive-definite "
           "3×3 tensor"},
          {"oneOf",
           json::array(
               {{{"type", "array"}, {"items", num}, {"minItems", 3}, {"maxItems", 3}},
                {{"type", "array"},
                 {"items", {{"type", "array"}, {"items", num}, {"minItems", 3}, {"maxItems", 3}}},
                 {"minItems", 3},
                 {"maxItems", 3}}})}};
}

bool read_preset(const json& v, const std::string& path, const std::vector<std::string>& names,
                 std::string& out, Errors& e) {
  if (!v.is_string()) {
    e.push_back({path, schema::detail::type_error("a string", v)});
    return false;
  }
  const std::string s = v.get<std::string>();
  if (std::find(names.begin(), names.end(), s) == names.end()) {
    e.push_back({path, "unknown preset \"" + s + "\" (supported: " + names_of(names) + ")" +
                           json_io::did_you_mean(s, names)});
    return false;
  }
  out = s;
  return true;
}

// A number, or an array of numbers: into `out`.
bool read_numbers(const json& v, const std::string& path, std::vector<double>& out, Errors& e) {
  if (v.is_number()) {
    double d = 0;
    if (!read_num(v, path, d, e)) return false;
    out = {d};
    return true;
  }
  if (!v.is_array() || v.empty()) {
    e.push_back(
        {path, "expected a number (every actuator's) or an array of one per actuator, got " +
                   json_io::json_type_name(v)});
    return false;
  }
  std::vector<double> x(v.size());
  bool ok = true;
  for (std::size_t i = 0; i < v.size(); ++i)
    ok = read_num(v[i], path + "/" + std::to_string(i), x[i], e) && ok;
  if (ok) out = std::move(x);
  return ok;
}

void read_actuators(const json& v, const std::string& path, sim::RigidBodySpec& s, Errors& e) {
  if (!v.is_object()) {
    e.push_back({path, "expected an object with \"axes\" (3 to 8 axes) or \"preset\" (" +
                           names_of(sim::body_presets()) + "), and optionally \"max\", got " +
                           json_io::json_type_name(v)});
    return;
  }
  unknown_keys(v, path, {"axes", "preset", "beta_deg", "max"}, e);
  const bool has_axes = v.contains("axes"), has_preset = v.contains("preset");
  if (has_axes == has_preset) {
    e.push_back({path, has_axes ? "give \"axes\" or \"preset\", not both"
                                : "needs \"axes\" (3 to 8 axes) or \"preset\" (" +
                                      names_of(sim::body_presets()) + ")"});
    return;
  }
  if (has_preset) {
    std::string p;
    if (!read_preset(v["preset"], path + "/preset", sim::body_presets(), p, e)) return;
    s.preset = p;
    s.axes.clear();
    s.beta_deg = sim::kPyramidBetaDeg;
  } else {
    const json& a = v["axes"];
    const std::string ap = path + "/axes";
    if (!a.is_array()) {
      e.push_back({ap, "expected an array of axes [x, y, z], got " + json_io::json_type_name(a)});
      return;
    }
    std::vector<std::array<double, 3>> axes(a.size());
    bool ok = true;
    for (std::size_t j = 0; j < a.size(); ++j) {
      const std::string jp = ap + "/" + std::to_string(j);
      if (!a[j].is_array() || a[j].size() != 3) {
        e.push_back({jp, "expected an axis [x, y, z], got " +
                             (a[j].is_array() ? "an array of " + std::to_string(a[j].size())
                                              : json_io::json_type_name(a[j]))});
        ok = false;
        continue;
      }
      for (std::size_t k = 0; k < 3; ++k)
        ok = read_num(a[j][k], jp + "/" + std::to_string(k), axes[j][k], e) && ok;
    }
    if (!ok) return;
    if (axes.size() < 3 || axes.size() > static_cast<std::size_t>(sim::kMaxBodyActuators)) {
      e.push_back({ap, "expected 3 to " + std::to_string(sim::kMaxBodyActuators) +
                           " actuator axes, got " + std::to_string(axes.size())});
      return;
    }
    s.preset.clear();
    s.axes = std::move(axes);
  }
  if (v.contains("beta_deg")) {
    if (s.preset != "pyramid")
      e.push_back({path + "/beta_deg", "applies to the pyramid preset only"});
    else
      read_num(v["beta_deg"], path + "/beta_deg", s.beta_deg, e);
  }
  s.max.clear();
  if (v.contains("max") && read_numbers(v["max"], path + "/max", s.max, e) && s.max.size() > 1 &&
      static_cast<int>(s.max.size()) != sim::actuator_count(s)) {
    e.push_back({path + "/max", "expected one limit for every actuator or one per actuator (" +
                                    std::to_string(sim::actuator_count(s)) + "), got " +
                                    std::to_string(s.max.size())});
    s.max.clear();
  }
}

json write_actuators(const sim::RigidBodySpec& s) {
  json o = json::object();
  if (!s.preset.empty()) {
    o["preset"] = s.preset;
    if (s.preset == "pyramid") o["beta_deg"] = s.beta_deg;
  } else {
    json axes = json::array();
    for (const auto& a : s.axes) axes.push_back(json::array({a[0], a[1], a[2]}));
    o["axes"] = axes;
  }
  if (s.max.size() == 1)
    o["max"] = s.max[0];
  else if (!s.max.empty())
    o["max"] = s.max;
  return o;
}

json actuators_schema() {
  const json num = {{"type", "number"}};
  const json axis = {{"type", "array"}, {"items", num}, {"minItems", 3}, {"maxItems", 3}};
  const json max = {
      {"description",
       "each actuator's limit |u_j| <= max_j in N·m (> 0): one number for every "
       "actuator or one per actuator; absent: no limit"},
      {"oneOf", json::array({{{"type", "number"}, {"exclusiveMinimum", 0}},
                             {{"type", "array"},
                              {"items", {{"type", "number"}, {"exclusiveMinimum", 0}}}}})}};
  return {{"type", "object"},
          {"description",
           "the actuators: actuator j applies u_j along its unit axis. Either \"axes\" (3 to 8 "
           "axes spanning R³) or \"preset\": orthogonal (the 3 body axes), pyramid (4 wheels at "
           "azimuths 45° + 90°(j − 1), elevation beta_deg, by default asin(1/√3) = 35.26°), nasa "
           "(the 3 body axes and (1, 1, 1)/√3)"},
          {"properties",
           {{"axes", {{"type", "array"}, {"items", axis}, {"minItems", 3}, {"maxItems", 8}}},
            {"preset", {{"enum", sim::body_presets()}}},
            {"beta_deg",
             {{"type", "number"},
              {"default", sim::kPyramidBetaDeg},
              {"description", "the pyramid wheels' elevation above the body x-y plane, degrees"}}},
            {"max", max}}},
          {"additionalProperties", false}};
}

void read_rotor(const json& v, const std::string& path, sim::RotorSpec& r, Errors& e) {
  if (!v.is_object()) {
    e.push_back({path,
                 "expected a rotor {\"position\": [x, y], \"spin\": \"cw\" or \"ccw\", "
                 "\"max_thrust\": N, \"moment_constant\": m}, got " +
                     json_io::json_type_name(v)});
    return;
  }
  unknown_keys(v, path, {"position", "spin", "max_thrust", "moment_constant"}, e);
  for (const char* key : {"position", "spin", "max_thrust", "moment_constant"})
    if (!v.contains(key)) e.push_back({path + "/" + key, "is required"});
  if (v.contains("position")) {
    const json& p = v["position"];
    if (!p.is_array() || p.size() != 2)
      e.push_back({path + "/position", "expected [x, y] in m (body frame), got " +
                                           (p.is_array() ? "an array of " + std::to_string(p.size())
                                                         : json_io::json_type_name(p))});
    else
      for (std::size_t k = 0; k < 2; ++k)
        read_num(p[k], path + "/position/" + std::to_string(k), r.position[k], e);
  }
  if (v.contains("spin")) {
    const json& s = v["spin"];
    const std::string got = s.is_string() ? s.get<std::string>() : "";
    if (got == "cw")
      r.spin = 1;
    else if (got == "ccw")
      r.spin = -1;
    else
      e.push_back({path + "/spin", s.is_string() ? schema::detail::choice_error({"cw", "ccw"}, got)
                                                 : schema::detail::type_error("a string", s)});
  }
  if (v.contains("max_thrust")) read_num(v["max_thrust"], path + "/max_thrust", r.max_thrust, e);
  if (v.contains("moment_constant"))
    read_num(v["moment_constant"], path + "/moment_constant", r.moment_constant, e);
}

void read_rotors(const json& v, const std::string& path, sim::MultirotorSpec& s, Errors& e) {
  if (v.is_array()) {
    if (v.size() < 4 || v.size() > static_cast<std::size_t>(sim::kMaxBodyActuators)) {
      e.push_back({path, "expected 4 to " + std::to_string(sim::kMaxBodyActuators) +
                             " rotors, got " + std::to_string(v.size())});
      return;
    }
    std::vector<sim::RotorSpec> rotors(v.size());
    const std::size_t before = e.size();
    for (std::size_t i = 0; i < v.size(); ++i)
      read_rotor(v[i], path + "/" + std::to_string(i), rotors[i], e);
    if (e.size() != before) return;
    s.preset.clear();
    s.rotors = std::move(rotors);
    return;
  }
  if (!v.is_object()) {
    e.push_back({path, "expected a list of rotors or a preset {\"preset\": " +
                           names_of(sim::rotor_presets()) +
                           ", \"arm_length\", \"max_thrust\", "
                           "\"moment_constant\"}, got " +
                           json_io::json_type_name(v)});
    return;
  }
  unknown_keys(v, path, {"preset", "arm_length", "max_thrust", "moment_constant"}, e);
  if (!v.contains("preset")) {
    e.push_back({path + "/preset",
                 "is required (" + names_of(sim::rotor_presets()) + "), or give a list of rotors"});
    return;
  }
  std::string p;
  if (!read_preset(v["preset"], path + "/preset", sim::rotor_presets(), p, e)) return;
  s.preset = p;
  s.rotors.clear();
  if (v.contains("arm_length")) read_num(v["arm_length"], path + "/arm_length", s.arm_length, e);
  if (v.contains("max_thrust")) read_num(v["max_thrust"], path + "/max_thrust", s.max_thrust, e);
  if (v.contains("moment_constant"))
    read_num(v["moment_constant"], path + "/moment_constant", s.moment_constant, e);
}

json write_rotors(const sim::MultirotorSpec& s) {
  if (!s.preset.empty())
    return {{"preset", s.preset},
            {"arm_length", s.arm_length},
            {"max_thrust", s.max_thrust},
            {"moment_constant", s.moment_constant}};
  json a = json::array();
  for (const sim::RotorSpec& r : s.rotors)
    a.push_back({{"position", json::array({r.position[0], r.position[1]})},
                 {"spin", r.spin < 0 ? "ccw" : "cw"},
                 {"max_thrust", r.max_thrust},
                 {"moment_constant", r.moment_constant}});
  return a;
}

json rotors_schema() {
  const sim::MultirotorSpec d;
  const json rotor = {
      {"type", "object"},
      {"required", json::array({"position", "spin", "max_thrust", "moment_constant"})},
      {"properties",
       {{"position",
         {{"type", "array"},
          {"items", {{"type", "number"}}},
          {"minItems", 2},
          {"maxItems", 2},
          {"description", "(x, y) in m, body frame, z up"}}},
        {"spin", {{"enum", json::array({"cw", "ccw"})}}},
        {"max_thrust", {{"type", "number"}, {"exclusiveMinimum", 0}, {"description", "N"}}},
        {"moment_constant",
         {{"type", "number"},
          {"exclusiveMinimum", 0},
          {"description", "m: N·m of drag torque per N of thrust"}}}}},
      {"additionalProperties", false}};
  const json preset = {{"type", "object"},
                       {"required", json::array({"preset"})},
                       {"properties",
                        {{"preset", {{"enum", sim::rotor_presets()}}},
                         {"arm_length",
                          {{"type", "number"},
                           {"exclusiveMinimum", 0},
                           {"default", d.arm_length},
                           {"description", "m"}}},
                         {"max_thrust",
                          {{"type", "number"},
                           {"exclusiveMinimum", 0},
                           {"default", d.max_thrust},
                           {"description", "N"}}},
                         {"moment_constant",
                          {{"type", "number"},
                           {"exclusiveMinimum", 0},
                           {"default", d.moment_constant},
                           {"description", "m"}}}}},
                       {"additionalProperties", false}};
  return {{"description",
           "the rotors: a list of 4 to 8, or a preset layout (quad_x: rotors at 45° + 90°(i − 1), "
           "quad_plus: 0° + 90°(i − 1), hexa_x: 30° + 60°(i − 1), the hexarotor's, octa_x: "
           "22.5° + 45°(i − 1); odd rotors clockwise); every rotor's hover thrust (the "
           "minimum-norm thrusts with zero torque that carry m g) must lie strictly inside "
           "(0, max_thrust)"},
          {"oneOf",
           json::array(
               {{{"type", "array"}, {"items", rotor}, {"minItems", 4}, {"maxItems", 8}}, preset})}};
}

using Field = schema::Object<sim::PlantSpec>::Field;

template <class Spec, class ToSpec>
Field spec_field(std::string key, ToSpec to_spec,
                 std::function<void(const json&, const std::string&, Spec&, Errors&)> read,
                 std::function<json(const Spec&)> write, std::function<json()> schema_of,
                 std::vector<double> defaults) {
  return {key,
          false,
          [to_spec, read](const json& v, const std::string& path, sim::PlantSpec& out, Errors& e) {
            Spec s = to_spec(out.values);
            const std::size_t before = e.size();
            read(v, path, s, e);
            if (e.size() == before) out.values = sim::to_values(s);
          },
          [](const sim::PlantSpec&, const std::string&, Errors&) {},  // the kind's check
          [key, to_spec, write, defaults](const sim::PlantSpec& c, json& o) {
            o[key] = write(to_spec(c.values.empty() ? defaults : c.values));
          },
          schema_of};
}

}  // namespace

namespace {

std::shared_ptr<schema::Object<sim::PlantSpec>> rigid_body_object(const sim::PlantKind& k) {
  auto o = std::make_shared<schema::Object<sim::PlantSpec>>(k.description);
  const auto to_spec = [](const std::vector<double>& v) { return sim::rigid_body_spec(v); };
  const std::vector<double> d = k.defaults();
  o->field(spec_field<sim::RigidBodySpec>(
      "inertia", to_spec,
      [](const json& v, const std::string& p, sim::RigidBodySpec& s, Errors& e) {
        read_inertia(v, p, s.inertia, e);
      },
      [](const sim::RigidBodySpec& s) { return write_inertia(s.inertia); }, inertia_schema, d));
  o->field(spec_field<sim::RigidBodySpec>(
      "actuators", to_spec, read_actuators,
      [](const sim::RigidBodySpec& s) { return write_actuators(s); }, actuators_schema, d));
  return o;
}

std::shared_ptr<schema::Object<sim::PlantSpec>> multirotor_object(const sim::PlantKind& k) {
  auto o = std::make_shared<schema::Object<sim::PlantSpec>>(k.description);
  const auto to_spec = [](const std::vector<double>& v) { return sim::multirotor_spec(v); };
  const std::vector<double> d = k.defaults();
  const sim::MultirotorSpec def;
  const auto number = [&](const char* key, double sim::MultirotorSpec::*m, const char* unit,
                          const char* doc) {
    o->field(spec_field<sim::MultirotorSpec>(
        key, to_spec,
        [m](const json& v, const std::string& p, sim::MultirotorSpec& s, Errors& e) {
          read_num(v, p, s.*m, e);
        },
        [m](const sim::MultirotorSpec& s) { return json(s.*m); },
        [unit, doc, dv = def.*m] {
          return json{{"type", "number"},
                      {"exclusiveMinimum", 0},
                      {"default", dv},
                      {"description", std::string(doc) + " (" + unit + ")"}};
        },
        d));
  };
  number("mass", &sim::MultirotorSpec::mass, "kg", "mass m (sets the hover thrusts)");
  number("gravity", &sim::MultirotorSpec::gravity, "m/s²", "gravitational acceleration g");
  o->field(spec_field<sim::MultirotorSpec>(
      "inertia", to_spec,
      [](const json& v, const std::string& p, sim::MultirotorSpec& s, Errors& e) {
        read_inertia(v, p, s.inertia, e);
      },
      [](const sim::MultirotorSpec& s) { return write_inertia(s.inertia); }, inertia_schema, d));
  o->field(spec_field<sim::MultirotorSpec>(
      "rotors", to_spec, read_rotors, [](const sim::MultirotorSpec& s) { return write_rotors(s); },
      rotors_schema, d));
  return o;
}

}  // namespace

std::shared_ptr<schema::Object<sim::PlantSpec>> structured_plant_object(const sim::PlantKind& k) {
  if (k.model == "rigid_body") return rigid_body_object(k);
  if (k.model == "multirotor") return multirotor_object(k);
  return nullptr;
}

bool read_tensor_values(const json& v, const std::string& path, std::vector<double>& out,
                        Errors& e) {
  if (!v.is_array() || v.empty() || !v[0].is_array()) return false;
  std::array<double, 9> J{};
  if (read_inertia(v, path, J, e)) out.assign(J.begin(), J.end());
  return true;
}

}  // namespace ftc::runtime::detail
