#pragma once
// The ETA `ftctune status` shows for a running service job, from the job's own JSON (GET
// /v1/jobs/{id}): the time it has run by its last progress update, scaled to the evaluations
// left. Times are the server's (started_at, updated_at), so the client's clock does not enter.
// Header-only: the tests check it without a server.
#include <cmath>
#include <cstdio>
#include <ctime>
#include <nlohmann/json.hpp>
#include <string>

namespace ftc::cli {

// "2026-11-23T14:00:00.123Z" as seconds since the epoch; NaN when it is not one.
inline double utc_seconds(const nlohmann::json& v) {
  if (!v.is_string()) return NAN;
  std::tm tm{};
  int ms = 0;
  if (std::sscanf(v.get<std::string>().c_str(), "%d-%d-%dT%d:%d:%d.%dZ", &tm.tm_year, &tm.tm_mon,
                  &tm.tm_mday, &tm.tm_hour, &tm.tm_min, &tm.tm_sec, &ms) < 6)
    return NAN;
  tm.tm_year -= 1900;
  tm.tm_mon -= 1;
  return static_cast<double>(timegm(&tm)) + ms / 1000.0;
}

// "  ETA 12 s" (or "3.5 min", "2.1 h") for a running job with progress; "" otherwise.
inline std::string eta_text(const nlohmann::json& job) {
  if (!job.is_object() || job.value("status", "") != "running" || !job.contains("progress"))
    return "";
  const nlohmann::json& p = job["progress"];
  // Past its last iteration: the comparison and the noise floor still run.
  if (p.is_object() && p.value("phase", "") == "finishing")
    return "  comparing controllers and measuring the noise floor";
  if (!p.is_object() || !p.value("evaluations", nlohmann::json()).is_number() ||
      !p.value("total_evaluations", nlohmann::json()).is_number())
    return "";
  const double done = p["evaluations"].get<double>(), total = p["total_evaluations"].get<double>();
  const double elapsed = utc_seconds(job.value("updated_at", nlohmann::json())) -
                         utc_seconds(job.value("started_at", nlohmann::json()));
  if (!(done > 0) || !(total > done) || !(elapsed >= 0)) return "";
  const double eta = elapsed * (total - done) / done;
  char buf[64];
  if (eta < 90)
    std::snprintf(buf, sizeof buf, "  ETA %.0f s", eta);
  else if (eta < 5400)
    std::snprintf(buf, sizeof buf, "  ETA %.1f min", eta / 60);
  else
    std::snprintf(buf, sizeof buf, "  ETA %.1f h", eta / 3600);
  return buf;
}

}  // namespace ftc::cli
