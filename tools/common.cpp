#include <spdlog/spdlog.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <nlohmann/json.hpp>

#include "cli.hpp"
#include "ftc/runtime/json_reader.hpp"
#include "ftc/tune/io/files.hpp"
#include "ftc/tune/run/tuning_run.hpp"

namespace ftc::cli {

using nlohmann::json;

sim::ControllerConfig select_controller(const tune::Job& job, const std::string& type,
                                        const std::vector<std::string>& sets) {
  sim::ControllerConfig base = job.controller;
  if (!type.empty()) {
    const auto t = sim::controller_type_from_string(type);
    if (!t)
      throw InputError("--controller", "",
                       "unknown controller type \"" + type + "\" (known: " +
                           std::string(sim::controller_type_list()) + ")");
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
    const std::string text = s.substr(eq + 1);
    const json v = json::parse(text, nullptr, false);
    if (v.is_discarded())  // a syntax error, or a number beyond the range of a double
      errs.push_back({key, "value \"" + json_io::printable(text) + "\" is not a finite number"});
    else
      j[key] = v;
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

CLI::Validator seed_value() {
  return CLI::Validator(
      [](std::string& s) -> std::string {
        errno = 0;
        char* end = nullptr;
        if (!s.empty() && s.find_first_not_of("0123456789") == std::string::npos) {
          std::strtoull(s.c_str(), &end, 10);
          if (errno == 0 && *end == '\0') return "";
        }
        return std::string("a seed is an integer in 0..18446744073709551615, got \"")
            .append(json_io::printable(s))
            .append("\"");
      },
      "SEED");
}

CLI::Validator output_directory() {
  return CLI::Validator([](std::string& s) { return tune::directory_problem(s); }, "DIR");
}

CLI::Validator output_file() {
  return CLI::Validator(
      [](std::string& s) -> std::string {
        const std::filesystem::path p(s);
        std::error_code ec;
        if (std::filesystem::is_directory(p, ec)) return s + " is a directory";
        try {
          tune::refuse_non_regular_target(p);  // a link, a device node, a FIFO: never replaced
        } catch (const std::exception& e) {
          return e.what();
        }
        return tune::directory_problem(p.has_parent_path() ? p.parent_path() : ".");
      },
      "FILE");
}

std::filesystem::path default_out_dir(const tune::Job& job) {
  return default_out_dir_for(job.name);
}

std::filesystem::path default_out_dir_for(const std::string& job_name) {
  return tune::default_out_dir(job_name);
}

tune::RunLog spdlog_log() {
  return [](tune::LogLevel level, const std::string& message) {
    if (level == tune::LogLevel::warn)
      spdlog::warn("{}", message);
    else
      spdlog::info("{}", message);
  };
}

}  // namespace ftc::cli
