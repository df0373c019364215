#include <nlohmann/json.hpp>

#include "cli.hpp"

namespace ftc::cli {

using nlohmann::json;

sim::ControllerConfig select_controller(const tune::Job& job, const std::string& type,
                                        const std::vector<std::string>& sets) {
  sim::ControllerConfig base = job.controller;
  if (!type.empty()) {
    const auto t = sim::controller_type_from_string(type);
    if (!t)
      throw InputError("--controller", "",
                       "unknown controller type \"" + type +
                           "\" (known: nftsmc, fosmc, pi_fosmc, "
                           "adaptive_neural_pi_fosmc)");
    base = sim::ControllerConfig::table1(*t);
  }
  if (sets.empty()) return base;

  json j = tune::to_json(base);
  std::vector<FieldError> errs;
  for (const std::string& s : sets) {
    const auto eq = s.find('=');
    if (eq == std::string::npos || eq == 0) {
      errs.push_back({"", "expected KEY=VALUE, got \"" + s + "\""});
      continue;
    }
    const std::string key = s.substr(0, eq);
    if (key == "type" || !j.contains(key)) {
      std::string names;
      for (const std::string& n : sim::controller_field_names(base.type))
        names += (names.empty() ? "" : ", ") + n;
      errs.push_back({key, "is not a parameter of controller " +
                               std::string(sim::to_string(base.type)) + " (parameters: " + names +
                               ")" +
                               json_io::did_you_mean(key, sim::controller_field_names(base.type))});
      continue;
    }
    try {
      j[key] = json::parse(s.substr(eq + 1));
    } catch (const json::parse_error&) {
      errs.push_back({key, "value \"" + s.substr(eq + 1) + "\" is not a number"});
    }
  }
  throw_if_errors("--set", errs);
  sim::ControllerConfig c = tune::parse_controller(j, "", errs);
  std::vector<FieldError> v = c.validate("");
  errs.insert(errs.end(), v.begin(), v.end());
  for (FieldError& e : errs)
    if (!e.path.empty() && e.path[0] == '/') e.path.erase(0, 1);
  throw_if_errors("--set", errs);
  return c;
}

std::filesystem::path default_out_dir(const tune::Job& job) {
  return default_out_dir_for(job.name);
}

}  // namespace ftc::cli
