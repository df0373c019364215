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

namespace {

// Why `dir` cannot be made into a directory to write in ("" when it can): it, or the nearest of
// its ancestors that exists, must be a directory this process may write to.
std::string directory_problem(const std::filesystem::path& dir) {
  namespace fs = std::filesystem;
  std::error_code ec;
  fs::path at = fs::absolute(dir, ec);
  if (ec) return ec.message();
  while (!fs::exists(at, ec) && at.has_parent_path() && at.parent_path() != at)
    at = at.parent_path();
  if (!fs::is_directory(at, ec))
    return at == fs::absolute(dir, ec) ? dir.string() + " exists and is not a directory"
                                       : std::string("cannot create ")
                                             .append(dir.string())
                                             .append(": ")
                                             .append(at.string())
                                             .append(" is not a directory");
  if (::access(at.c_str(), W_OK | X_OK) != 0)
    return std::string("cannot write in ")
        .append(at.string())
        .append(": ")
        .append(std::strerror(errno));
  return "";
}

}  // namespace

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
  return CLI::Validator([](std::string& s) { return directory_problem(s); }, "DIR");
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
        return directory_problem(p.has_parent_path() ? p.parent_path() : ".");
      },
      "FILE");
}

std::filesystem::path default_out_dir(const tune::Job& job) {
  return default_out_dir_for(job.name);
}

std::filesystem::path latest_run_dir(const tune::Job& job, std::string* why) {
  namespace fs = std::filesystem;
  const fs::path base = default_out_dir(job);
  const std::string prefix = base.filename().string() + "-";
  struct Found {
    fs::path dir;
    fs::file_time_type time;
    int suffix = 1;
    bool same_job = false;
  };
  std::vector<Found> runs;
  std::error_code ec;
  const auto consider = [&](const fs::path& dir, int suffix) {
    const fs::path gains = dir / "gains.json";
    std::error_code e;
    const fs::file_time_type t = fs::last_write_time(gains, e);
    if (e || !fs::is_regular_file(gains, e)) return;
    bool same = false;
    if (const std::optional<std::string> text = tune::read_file(gains)) {
      const json g = json::parse(*text, nullptr, false);
      same = g.is_object() && g.contains("job") && g["job"].is_object() &&
             g["job"].value("sha256", "") == tune::canonical_job_sha256(job);
    }
    runs.push_back({dir, t, suffix, same});
  };
  consider(base, 1);
  for (fs::directory_iterator it(base.parent_path(), ec), end; !ec && it != end; it.increment(ec)) {
    const std::string name = it->path().filename().string();
    if (name.size() <= prefix.size() || name.compare(0, prefix.size(), prefix) != 0) continue;
    const std::string digits = name.substr(prefix.size());
    if (digits.size() > 6 || digits.find_first_not_of("0123456789") != std::string::npos ||
        digits[0] == '0')
      continue;
    consider(it->path(), std::stoi(digits));
  }
  if (runs.empty()) {
    if (why) *why = "no run of job " + job.name + " in " + base.parent_path().string();
    return {};
  }
  const bool any_same =
      std::any_of(runs.begin(), runs.end(), [](const Found& f) { return f.same_job; });
  const Found* best = nullptr;
  for (const Found& f : runs)
    if ((f.same_job || !any_same) &&
        (!best || f.time > best->time || (f.time == best->time && f.suffix > best->suffix)))
      best = &f;
  if (why)
    *why =
        "the latest run of job " + job.name + " is " + best->dir.string() +
        (any_same ? "" : " (of another version of the job file: its SHA-256 differs)") +
        (runs.size() > 1 ? " (newest gains.json of " + std::to_string(runs.size()) + " runs)" : "");
  return best->dir;
}

}  // namespace ftc::cli
