#include "ftc/runtime/controller_json.hpp"

#include <cmath>
#include <nlohmann/json.hpp>

#include "ftc/runtime/json_reader.hpp"

namespace ftc::runtime {

using json_io::ObjectReader;
using nlohmann::json;

sim::ControllerConfig parse_controller(const json& j, const std::string& path,
                                       std::vector<FieldError>& errs) {
  sim::ControllerConfig c;
  ObjectReader r(j, path, errs);
  if (!r.ok()) return c;
  std::string type;
  if (!r.string("type", type, true)) return c;
  const auto t = sim::controller_type_from_string(type);
  if (!t) {
    errs.push_back(
        {r.path("type"), "unknown controller type \"" + type +
                             "\" (known: nftsmc, fosmc, pi_fosmc, adaptive_neural_pi_fosmc)"});
    return c;
  }
  c = sim::ControllerConfig::table1(*t);
  for (const sim::ControllerField& f : sim::controller_fields()) {
    if (!f.applies_to(*t)) continue;
    double v = 0;
    if (!r.number(f.name, v)) continue;
    if (f.integer && v != std::floor(v)) {
      errs.push_back({r.path(f.name), "expected an integer, got " + json_io::number_text(v)});
      continue;
    }
    c.*f.member = v;
  }
  if (*t == sim::ControllerType::adaptive_neural_pi_fosmc)
    r.numbers("centre_range", c.centre_range.data(), 2);
  for (const std::string& k : r.keys()) {
    const sim::ControllerField* f = sim::find_controller_field(k);
    const bool other = (f && !f->applies_to(*t)) ||
                       (k == "centre_range" && *t != sim::ControllerType::adaptive_neural_pi_fosmc);
    if (other) {
      errs.push_back({r.path(k.c_str()), "does not apply to controller type " + type});
      r.mark_seen(k);
    }
  }
  r.finish();
  return c;
}

json to_json(const sim::ControllerConfig& c) {
  json j;
  j["type"] = sim::to_string(c.type);
  for (const sim::ControllerField& f : sim::controller_fields()) {
    if (!f.applies_to(c.type)) continue;
    double v = c.*f.member;
    if (f.optional && std::isnan(v)) v = c.resolved_alpha1();
    if (f.integer)
      j[f.name] = static_cast<long long>(v);
    else
      j[f.name] = v;
  }
  if (c.type == sim::ControllerType::adaptive_neural_pi_fosmc)
    j["centre_range"] = {c.centre_range[0], c.centre_range[1]};
  return j;
}

}  // namespace ftc::runtime
