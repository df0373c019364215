#include "service/api.hpp"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <openssl/crypto.h>
#include <spdlog/spdlog.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <new>
#include <nlohmann/json.hpp>

#include "ftc/runtime/json_reader.hpp"
#include "ftc/sim/metrics_record.hpp"
#include "ftc/sim/plant_plugin.hpp"
#include "ftc/tune/api/api.hpp"
#include "ftc/tune/io/files.hpp"
#include "ftc/tune/job/ensemble.hpp"
#include "ftc/tune/job/job.hpp"
#include "ftc/tune/report/report.hpp"
#include "ftc/tune/run/documents.hpp"
#include "ftc/tune/run/front.hpp"
#include "ftc/tune/run/memory_budget.hpp"
#include "ftc/tune/run/tuning_run.hpp"
#include "ftc/version.hpp"
#include "service/http_server.hpp"
#include "service/web_assets.hpp"

namespace ftc::tune::service_detail {

using nlohmann::json;

namespace {

// Responses never fail to encode: a message that quotes request bytes which are not UTF-8 (a
// path, a header) gets U+FFFD in their place instead of a 500.
std::string encode(const json& body) {
  return body.dump(-1, ' ', false, json::error_handler_t::replace);
}

void send_error(httplib::Response& res, int status, const std::string& code,
                const std::string& message, json details = json::array()) {
  res.status = status;
  res.set_content(
      encode(json{{"error", {{"code", code}, {"message", message}, {"details", details}}}}),
      "application/json");
}

void send_json(httplib::Response& res, int status, const json& body) {
  res.status = status;
  res.set_content(encode(body), "application/json");
}

json nullable(const std::string& s) { return s.empty() ? json(nullptr) : json(s); }

// A job's stored files written out as the run directory they came from, for the library's
// readers of run directories (report.html, pick): in a fresh directory only this process can
// read (mkdtemp, 0700), removed with the object, or if writing them fails. `names`: only these
// files (all when empty). A stored name is the run's own (safe_name'd job and scenario names),
// and one that would leave the directory is refused all the same.
struct RunDirectory {
  std::filesystem::path path;
  RunDirectory(JobStore& store, const std::string& id, const std::vector<std::string>& names = {}) {
    std::string pattern = (std::filesystem::temp_directory_path() / "ftctune-run-XXXXXX").string();
    if (!::mkdtemp(pattern.data()))
      throw std::runtime_error("cannot make a temporary directory: " +
                               std::string(std::strerror(errno)));
    path = pattern;
    try {
      const auto write = [&](const std::string& name, const std::string& content) {
        const std::filesystem::path rel(name);
        for (const auto& part : rel)
          if (part == ".." || rel.is_absolute())
            throw std::runtime_error("job " + id + " has a stored file named " + name);
        write_file_atomic(path / rel, content);
      };
      if (names.empty()) {
        for (const auto& [name, content] : store.artifacts(id)) write(name, content);
      } else {
        for (const std::string& name : names)
          if (const std::optional<std::string> content = store.artifact(id, name))
            write(name, *content);
      }
    } catch (...) {
      std::error_code ec;
      std::filesystem::remove_all(path, ec);
      throw;
    }
  }
  RunDirectory(const RunDirectory&) = delete;
  RunDirectory& operator=(const RunDirectory&) = delete;
  ~RunDirectory() {
    std::error_code ec;
    std::filesystem::remove_all(path, ec);
  }
};

json job_links(const std::string& id) {
  const std::string base = "/v1/jobs/" + id;
  return {{"self", base},
          {"job", base + "/job"},
          {"gains", base + "/gains"},
          {"history", base + "/history"},
          {"trials", base + "/trials"},
          {"comparison", base + "/comparison"},
          {"report", base + "/report"},
          {"files", base + "/files"},
          {"events", base + "/events"},
          {"cancel", base + "/cancel"}};
}

json job_json_view(const JobRecord& r) {
  json progress = {{"iteration", r.iteration >= 0 ? json(r.iteration) : json(nullptr)},
                   {"iterations", r.iterations},
                   {"evaluations", r.evaluations},
                   {"total_evaluations", r.total_evaluations},
                   {"best_fitness", r.best_fitness ? json(*r.best_fitness) : json(nullptr)},
                   {"best", r.best}};
  // A running job past its last iteration still compares the controllers and measures the noise
  // floor: its evaluations are all done, and it is not about to finish (issue 41).
  if (r.status == JobStatus::running)
    progress["phase"] = r.iteration >= r.iterations ? "finishing" : "tuning";
  return {{"id", r.id},
          {"name", r.name},
          {"status", to_string(r.status)},
          {"created_at", r.created_at},
          {"started_at", nullable(r.started_at)},
          {"finished_at", nullable(r.finished_at)},
          {"updated_at", r.updated_at},
          {"progress", progress},
          {"cancel_requested", r.cancel_requested},
          {"attempts", r.attempts},
          {"error", nullable(r.error)},
          // What J measures (a jobs list compares J within one measure), and how many warnings a
          // succeeded run's gains file lists (the dashboard's "succeeded with warnings"; null:
          // not counted, a job finished under an older server).
          {"objective", r.objective},
          {"warnings", r.warnings >= 0 ? json(r.warnings) : json(nullptr)},
          // Results so far (gains, history, trials) of a job that ran an iteration but did not
          // finish it all: running, or cancelled.
          {"partial", r.iteration >= 0 &&
                          (r.status == JobStatus::running || r.status == JobStatus::cancelled)},
          {"links", job_links(r.id)}};
}

// GET /v1/metrics: the metrics record (kMetricFields), what the dashboard names and tabulates a
// run's metrics by: each field's name (the JSON key of comparison.json), label, unit, scope
// (window, run or fault: one value per fault onset), whether comparison.md tabulates it, and
// whether a job may name it as a goal or its objective.
json metrics_list() {
  static const char* const kScopes[] = {"window", "run", "fault"};  // MetricScope's order
  json list = json::array();
  for (const sim::MetricField& f : sim::kMetricFields)
    list.push_back({{"name", f.name},
                    {"label", sim::plain_label(f)},
                    {"unit", f.unit},
                    {"scope", kScopes[static_cast<int>(f.scope)]},
                    {"in_tables", f.in_tables},
                    {"goal", f.goal},
                    {"objective", f.objective}});
  return {{"metrics", list}};
}

// A stored file's media type, from its name.
const char* media_type(const std::string& name) {
  const auto ends = [&](const char* ext) {
    const std::size_t n = std::strlen(ext);
    return name.size() >= n && name.compare(name.size() - n, n, ext) == 0;
  };
  if (ends(".json")) return "application/json";
  if (ends(".csv")) return "text/csv";
  if (ends(".md")) return "text/markdown; charset=utf-8";
  if (ends(".html")) return "text/html; charset=utf-8";
  if (ends(".png")) return "image/png";
  if (ends(".svg")) return "image/svg+xml";
  return "application/octet-stream";
}

json history_rows(const TuningOutcome& r) {
  json rows = json::array();
  std::vector<std::string> names;
  for (const ParameterBounds& b : r.job.tuning->parameters) names.push_back(b.name);
  for (const HistoryRow& h : r.optimization.history) {
    json best = json::object();
    for (std::size_t i = 0; i < names.size() && i < h.best.size(); ++i)
      best[names[i]] = json_io::json_number(h.best[i]);
    json row = {{"iteration", h.iteration},
                {"best_fitness", json_io::json_number(h.best_fitness)},
                {"best", best},
                {"evaluations", h.evaluations}};
    for (const auto& [name, value] : h.extras) row[name] = json_io::json_number(value);
    rows.push_back(std::move(row));
  }
  return rows;
}

std::string fmt_g(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.3g", v);
  return buf;
}

bool parse_int(const std::string& s, long long lo, long long hi, long long& out) {
  if (s.empty() || s.size() > 12) return false;
  char* end = nullptr;
  const long long v = std::strtoll(s.c_str(), &end, 10);
  if (*end != '\0' || v < lo || v > hi) return false;
  out = v;
  return true;
}

std::vector<std::string> split_path(const std::string& path) {
  std::vector<std::string> parts;
  std::size_t i = 0;
  while (i < path.size()) {
    while (i < path.size() && path[i] == '/') ++i;
    const std::size_t j = path.find('/', i);
    if (i < path.size())
      parts.push_back(path.substr(i, j == std::string::npos ? std::string::npos : j - i));
    i = j == std::string::npos ? path.size() : j;
  }
  return parts;
}

std::string megabytes(double bytes) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.1f MB", bytes / 1e6);
  return buf;
}

// The numbers in a job's result files: its comparison trajectories (the rows the service
// records) and trials.csv (a row per evaluation).
double result_numbers(const Job& job, std::int64_t trajectory_rows) {
  // iteration, index, the parameters, objective, fitness, diverged, accepted.
  const double trial_numbers = 6.0 + static_cast<double>(job.tuning->parameters.size());
  return comparison_trajectory_numbers(job, trajectory_rows) +
         static_cast<double>(job.tuning->algorithm->evaluations()) * trial_numbers;
}

// A low estimate of the bytes of a job's result files, fewer than the ~12 a number takes in the
// Table 1 job's files: it refuses at once a job that could only fail at its end; the runner
// checks the real size.
constexpr double kStoredBytesPerNumber = 8.0;
// What the service holds of a job's result files besides what the run made, its copy handed to
// the store: a job of 6 scenarios of 200 s and 12 controllers stored 278.1 MB for 21.6e6
// numbers (12.9 each), and peaked the server 283 MB above `ftctune run`'s 713 MB.
constexpr double kHeldBytesPerNumber = 13.0;

std::string seconds_text(double s) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g s", s);
  return buf;
}

// The dashboard's file at `path`, if it is one: served to anyone (it holds no data; the page asks
// for the token), with a policy that lets it run only its own scripts.
const WebAsset* web_asset(const std::string& path) {
  for (const WebAsset& a : web_assets())
    if (path == a.path) return &a;
  return nullptr;
}

bool serve_asset(const httplib::Request& req, httplib::Response& res) {
  if (req.method != "GET" && req.method != "HEAD") return false;
  const WebAsset* a = web_asset(req.path);
  if (!a) return false;
  std::string type = a->type;
  if (type.rfind("text/", 0) == 0) type += "; charset=utf-8";
  res.status = 200;
  res.set_content(reinterpret_cast<const char*>(a->data), a->size, type.c_str());
  res.set_header("Cache-Control", "no-cache");
  return true;
}

// What a page may do: its own scripts, styles and requests only; nothing inline, no frames, no
// other origin. The dashboard's files get it, and every other answer a stricter one.
constexpr const char* kPagePolicy =
    "default-src 'none'; script-src 'self'; style-src 'self'; img-src 'self' data: blob:; "
    "connect-src 'self'; base-uri 'none'; form-action 'none'; frame-ancestors 'none'";
// report.html is one self-contained page: its own style and inline images, no script at all.
constexpr const char* kReportPolicy =
    "default-src 'none'; style-src 'unsafe-inline'; img-src data:; base-uri 'none'; "
    "form-action 'none'; frame-ancestors 'none'";
constexpr const char* kDataPolicy = "default-src 'none'; frame-ancestors 'none'";

std::string lower(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

// The host of a Host header's value ("localhost:8080" -> "localhost", "[::1]:80" -> "[::1]"),
// lower-case.
std::string host_name(const std::string& host) {
  if (!host.empty() && host.front() == '[') {
    const std::size_t end = host.find(']');
    return lower(host.substr(0, end == std::string::npos ? host.size() : end + 1));
  }
  return lower(host.substr(0, host.find(':')));
}

// A name a browser only ever resolves to this machine: localhost (and *.localhost, RFC 6761),
// an IPv4 address of 127.0.0.0/8, or [::1]; or the address the server is bound to.
bool loopback_host(const std::string& name, const std::string& bind) {
  const std::string suffix = ".localhost";
  if (name == "localhost" || name == "[::1]" ||
      (name.size() > suffix.size() &&
       name.compare(name.size() - suffix.size(), suffix.size(), suffix) == 0))
    return true;
  in_addr a{};
  if (::inet_pton(AF_INET, name.c_str(), &a) == 1) return (ntohl(a.s_addr) >> 24) == 127;
  const std::string b = lower(bind);
  return name == b || name == "[" + b + "]";
}

// A request a page of another origin sent: its Origin is not this service's (http://<Host>), or,
// without an Origin, the browser says it is cross-site.
bool cross_origin(const httplib::Request& req) {
  // A browser that says the request is cross-site is believed even when the Origin it sends
  // matches (the two cannot both be true of one page).
  if (lower(req.get_header_value("Sec-Fetch-Site")) == "cross-site") return true;
  return req.has_header("Origin") &&
         lower(req.get_header_value("Origin")) != "http://" + lower(req.get_header_value("Host"));
}

// A peer address of this machine's loopback: 127.0.0.0/8, ::1 or an IPv4-mapped 127.x.
bool loopback_address(const std::string& address) {
  in_addr a{};
  if (::inet_pton(AF_INET, address.c_str(), &a) == 1) return (ntohl(a.s_addr) >> 24) == 127;
  in6_addr b{};
  if (::inet_pton(AF_INET6, address.c_str(), &b) == 1)
    return IN6_IS_ADDR_LOOPBACK(&b) || (IN6_IS_ADDR_V4MAPPED(&b) && b.s6_addr[12] == 127);
  return false;
}

}  // namespace

json Api::view(const JobRecord& r) {
  json j = job_json_view(r);
  j["unstored"] = nullptr;
  if (const std::optional<Unstored> u = runner_.unstored(r.id))
    j["unstored"] = {{"status", to_string(u->status)},
                     {"finished_at", u->finished_at},
                     {"bytes", u->bytes},
                     {"error", nullable(u->error)}};
  if (runner_.cancel_deferred(r.id)) j["cancel_requested"] = true;
  return j;
}

void Api::insufficient_storage(httplib::Response& res, const std::string& why) {
  const StoreHealth h = runner_.health();
  std::string message = "the job store cannot write (" + why + ")";
  if (h.unstored > 0)
    message += "; " + std::to_string(h.unstored) + " finished job" + (h.unstored == 1 ? "" : "s") +
               " wait" + (h.unstored == 1 ? "s" : "") + " in memory to be stored";
  message += ": free space where the store is; the server tries again every " +
             seconds_text(opt_.store_retry_seconds);
  res.set_header("Retry-After",
                 std::to_string(static_cast<long>(std::ceil(opt_.store_retry_seconds))));
  send_error(res, 507, "insufficient_storage", message,
             json{{"unstored_jobs", h.unstored}, {"unrecorded_cancels", h.cancels}});
}

bool Api::authorised(const httplib::Request& req) const {
  if (!opt_.token) return true;
  const std::string expected = "Bearer " + *opt_.token;
  const std::string got = req.get_header_value("Authorization");
  // Constant time in the token's content; only the length can leak.
  return got.size() == expected.size() &&
         CRYPTO_memcmp(got.data(), expected.data(), got.size()) == 0;
}

void Api::method_not_allowed(httplib::Response& res, const char* allow) {
  res.set_header("Allow", allow);
  send_error(res, 405, "method_not_allowed", std::string("this resource allows ") + allow);
}

void Api::dispatch(const httplib::Request& req, httplib::Response& res) {
  if (serve_asset(req, res)) return;
  const std::vector<std::string> p = split_path(req.path);
  const std::string& m = req.method;
  if (p.size() == 1 && p[0] == "healthz") {
    if (m != "GET") return method_not_allowed(res, "GET");
    const StoreHealth h = runner_.health();
    const Checker::Counts checks = checker_.counts();
    const bool writable = !h.error && !h.owes();
    return send_json(res, 200,
                     {{"status", writable ? "ok" : "degraded"},
                      {"version", kVersion},
                      {"queued", store_.count(JobStatus::queued)},
                      {"running", store_.count(JobStatus::running)},
                      {"store",
                       {{"writable", writable},
                        {"error", h.error ? json(*h.error) : json(nullptr)},
                        {"unstored_jobs", h.unstored},
                        {"unrecorded_cancels", h.cancels}}},
                      {"event_streams", hub_.open_streams()},
                      {"checks",
                       {{"queued", checks.queued},
                        {"running", checks.running},
                        {"abandoned", checks.abandoned},
                        {"skipped", checks.skipped}}}});
  }
  if (p.size() == 2 && p[0] == "v1" && p[1] == "events") {
    if (m != "GET") return method_not_allowed(res, "GET");
    return events(req, req.has_param("job") ? req.get_param_value("job") : "", res);
  }
  if (p.size() == 2 && p[0] == "v1" && p[1] == "metrics") {
    if (m != "GET") return method_not_allowed(res, "GET");
    return send_json(res, 200, metrics_list());
  }
  if (p.size() == 2 && p[0] == "v1" && p[1] == "validate") {
    if (m != "POST") return method_not_allowed(res, "POST");
    return validate(req, res);
  }
  if (p.size() < 2 || p[0] != "v1" || p[1] != "jobs")
    return send_error(res, 404, "not_found", "no such resource: " + req.path);
  if (p.size() == 2) {
    if (m == "POST") return submit(req, res);
    if (m == "GET") return list(req, res);
    return method_not_allowed(res, "GET, POST");
  }
  const std::string& id = p[2];
  if (p.size() == 3) {
    if (m == "DELETE") {
      const JobStore::Removal removal = store_.remove(id);
      runner_.store_wrote();
      switch (removal) {
        case JobStore::Removal::not_found:
          return send_error(res, 404, "not_found", "no job " + id);
        case JobStore::Removal::active:
          return send_error(res, 409, "conflict",
                            "job " + id +
                                " is queued or running: cancel it, and delete it once "
                                "it has stopped");
        case JobStore::Removal::removed:
          spdlog::info("job {} deleted", id);
          changed(id);
          return send_json(res, 200, {{"id", id}, {"deleted", true}});
      }
    }
    if (m != "GET") return method_not_allowed(res, "GET, DELETE");
    const auto job = store_.get(id);
    if (!job) return send_error(res, 404, "not_found", "no job " + id);
    return send_json(res, 200, view(*job));
  }
  if (p.size() == 4 && p[3] == "events") {
    if (m != "GET") return method_not_allowed(res, "GET");
    return events(req, id, res);
  }
  if (p.size() == 4 && p[3] == "cancel") {
    if (m != "POST") return method_not_allowed(res, "POST");
    return cancel(id, res);
  }
  if (p.size() >= 4 && p[3] == "files") {
    if (m != "GET") return method_not_allowed(res, "GET");
    std::string name;
    for (std::size_t i = 4; i < p.size(); ++i) name += (name.empty() ? "" : "/") + p[i];
    return files(id, name, res);
  }
  if (p.size() == 4 && p[3] == "job") {
    // The job as the server validated and stored it (canonical JSON): its search space's scales
    // for the dashboard's axes, or a file to submit again.
    if (m != "GET") return method_not_allowed(res, "GET");
    // (Read once: a job deleted meanwhile has none.)
    const std::string text = store_.job_json(id);
    if (text.empty()) return send_error(res, 404, "not_found", "no job " + id);
    return res.set_content(text, "application/json");
  }
  if (p.size() == 4 && p[3] == "held-out") {
    if (m != "GET") return method_not_allowed(res, "GET");
    return held_out(req, res, id);
  }
  if (p.size() == 4 && (p[3] == "gains" || p[3] == "history" || p[3] == "trials" ||
                        p[3] == "comparison" || p[3] == "report")) {
    if (m != "GET") return method_not_allowed(res, "GET");
    return result(req, res, id, p[3]);
  }
  send_error(res, 404, "not_found", "no such resource: " + req.path);
}

std::optional<Job> Api::check_job(const std::string& text, httplib::Response& res) const {
  const auto bad_request = [&](const char* code, const InputError& e) {
    json details = json::array();
    const std::size_t listed = std::min(e.errors().size(), kMaxReportedErrors);
    for (std::size_t i = 0; i < listed; ++i)
      details.push_back({{"path", e.errors()[i].path}, {"message", e.errors()[i].message}});
    json error = {{"code", code}, {"message", e.what()}, {"details", details}};
    // The rest counted, not listed (the message says how many there are in all).
    if (listed < e.errors().size()) error["details_omitted"] = e.errors().size() - listed;
    send_json(res, 400, {{"error", error}});
  };
  json body;
  try {
    body = json_io::parse_json_text(text, "request body");
  } catch (const InputError& e) {
    bad_request("invalid_json", e);
    return std::nullopt;
  }
  // A job may name only the plant plugins the server was started with (serve --plugin): any
  // other is refused as such, 422, before anything else of the job is read.
  if (body.is_object() && body.contains("plant") && body["plant"].is_object())
    if (const auto it = body["plant"].find("model");
        it != body["plant"].end() && it->is_string() &&
        it->get<std::string>().rfind(sim::kPluginPrefix, 0) == 0)
      try {
        sim::find_plant_plugin(it->get<std::string>());
      } catch (const InputError& e) {
        const std::string message = e.errors().front().message;
        send_error(res, 422, "plugin_not_loaded", "request body: /plant/model: " + message,
                   json::array({{{"path", "/plant/model"}, {"message", message}}}));
        return std::nullopt;
      }
  Job job;
  try {
    job = parse_job(body, "request body");
  } catch (const InputError& e) {
    bad_request("invalid_job", e);
    return std::nullopt;
  }
  if (!job.tuning) {
    send_error(res, 400, "invalid_job", "request body: /tuning: is required to tune",
               json::array({{{"path", "/tuning"}, {"message", "is required to tune"}}}));
    return std::nullopt;
  }
  // Priced by what a step costs: a step with f faults is 1 + f·kFaultStepCost fault-free ones
  // (a job of 15 000 faults was admitted on its plain step count and took 45 s an iteration).
  const double steps = static_cast<double>(job.tuning->algorithm->evaluations()) *
                       job.step_cost_per_evaluation();
  if (steps > opt_.max_steps) {
    send_error(res, 400, "job_too_large",
               "the job needs " + fmt_g(steps) +
                   " simulated steps (evaluations x steps per evaluation, a step with f faults "
                   "counting as 1 + f/" +
                   std::to_string(static_cast<int>(1.0 / kFaultStepCost)) + "), " +
                   fmt_g(steps / opt_.max_steps) + " times the server's budget of " +
                   fmt_g(opt_.max_steps),
               json{{{"steps", steps}, {"budget", opt_.max_steps}}});
    return std::nullopt;
  }

  // Memory by design: what the run would hold, estimated before it is queued.
  const double numbers = result_numbers(job, opt_.trajectory_rows);
  const double held = kHeldBytesPerNumber * numbers;
  if (const double need = estimated_run_bytes(job) + held;
      need > static_cast<double>(opt_.max_job_memory_bytes)) {
    send_error(
        res, 413, "job_too_large",
        "the job would need about " + bytes_text(need) + " of memory (" +
            memory_need_text(
                job, job.tuning ? static_cast<double>(job.tuning->algorithm->evaluations()) : 1.0) +
            ", its result files held to be stored at about " + bytes_text(held) +
            "), above the server's limit of " +
            bytes_text(static_cast<double>(opt_.max_job_memory_bytes)) +
            " per job: ask for fewer ensemble members, scenarios or evaluations, or a "
            "smaller population",
        json{{"bytes", need}, {"limit", opt_.max_job_memory_bytes}});
    return std::nullopt;
  }
  if (const double bytes = kStoredBytesPerNumber * numbers;
      bytes > static_cast<double>(opt_.max_stored_bytes)) {
    send_error(res, 400, "job_too_large",
               "the job's results would take at least " + megabytes(bytes) +
                   " (its comparison trajectories and trials), above the server's limit "
                   "of " +
                   megabytes(static_cast<double>(opt_.max_stored_bytes)) +
                   " per job: ask for fewer evaluations, scenarios or compared controllers",
               json{{"bytes", bytes}, {"limit", opt_.max_stored_bytes}});
    return std::nullopt;
  }
  return job;
}

std::optional<Job> Api::checked_job(const httplib::Request& req, httplib::Response& res) {
  // Owned by the check, which may outlive this request when it gives up.
  struct Check {
    std::string body;
    httplib::Response res;
    std::optional<Job> job;
  };
  auto check = std::make_shared<Check>();
  check->body = req.body;
  const auto deadline =
      std::chrono::steady_clock::now() +
      std::chrono::milliseconds(std::llround(opt_.check_timeout * 1000));
  switch (checker_.run([this, check] { check->job = check_job(check->body, check->res); },
                       deadline, [] { return GuardedServer::peer_closed(); })) {
    case Checker::Outcome::done:
      res.status = check->res.status;
      for (const auto& h : check->res.headers) res.headers.insert(h);
      res.body = std::move(check->res.body);
      return std::move(check->job);
    case Checker::Outcome::timed_out:
      res.set_header("Retry-After", "10");
      send_error(res, 503, "check_timeout",
                 "the job was not checked within " + seconds_text(opt_.check_timeout) +
                     " (--check-timeout; the server checks one job at a time, in order of "
                     "arrival): try again later, or send a smaller job");
      return std::nullopt;
    case Checker::Outcome::client_left:
      spdlog::info("{}: the client hung up before its job was checked", req.remote_addr);
      res.status = 400;  // nobody reads it
      return std::nullopt;
  }
  return std::nullopt;
}

// The checks of a submission, without submitting: 200 with what the job would be, or the
// same 400 a submission gets.
void Api::validate(const httplib::Request& req, httplib::Response& res) {
  const std::optional<Job> job = checked_job(req, res);
  if (!job) return;
  json parameters = json::array();
  for (const ParameterBounds& b : job->tuning->parameters) parameters.push_back(b.name);
  send_json(res, 200,
            {{"valid", true},
             {"name", job->name},
             {"parameters", parameters},
             {"iterations", job->tuning->algorithm->iterations()},
             {"total_evaluations", job->tuning->algorithm->evaluations()},
             {"steps", static_cast<double>(job->tuning->algorithm->evaluations()) *
                           static_cast<double>(job->steps_per_evaluation())},
             {"step_cost", static_cast<double>(job->tuning->algorithm->evaluations()) *
                               job->step_cost_per_evaluation()}});
}

void Api::submit(const httplib::Request& req, httplib::Response& res) {
  const std::optional<Job> checked = checked_job(req, res);
  if (!checked) return;
  const Job& job = *checked;
  // A store that owes finished jobs their results takes no new ones until it has written them.
  if (const StoreHealth h = runner_.health(); h.owes())
    return insufficient_storage(res, h.error.value_or("it has refused writes"));

  Submission s;
  s.client = req.remote_addr;
  s.job_json = to_json(job).dump();
  s.name = job.name;
  s.objective = fitness_label(job);
  s.iterations = job.tuning->algorithm->iterations();
  s.total_evaluations = job.tuning->algorithm->evaluations();
  const std::string key = req.get_header_value("Idempotency-Key");
  if (!key.empty()) {
    if (key.size() > 200)
      return send_error(res, 400, "invalid_header",
                        "Idempotency-Key is longer than 200 characters");
    s.idempotency_key = key;
  }
  const Submitted done = store_.submit(s, {opt_.max_queued, opt_.max_queued_per_client});
  runner_.store_wrote();
  const JobRecord& record = done.record;
  const bool created = done.created;
  if (done.refused != Submitted::Refusal::none) {
    // A queue slot frees when a job starts; a minute is a guess at when, not a promise.
    res.set_header("Retry-After", "60");
    if (done.refused == Submitted::Refusal::client_quota)
      return send_error(res, 429, "too_many_jobs",
                        "this client (" + s.client + ") has " + std::to_string(done.queued) +
                            " jobs queued, the most the server queues per client "
                            "(--max-queued-per-client): submit more once some have started",
                        json{{"queued", done.queued}, {"limit", opt_.max_queued_per_client}});
    return send_error(res, 503, "queue_full",
                      "the queue holds " + std::to_string(done.queued) +
                          " jobs, the most the server queues (--max-queued): try again later",
                      json{{"queued", done.queued}, {"limit", opt_.max_queued}});
  }
  if (!created && store_.job_json(record.id) != s.job_json)
    return send_error(
        res, 409, "idempotency_conflict",
        "Idempotency-Key was already used for job " + record.id + " with a different job");
  if (created) {
    spdlog::info("job {} ({}) queued", record.id, record.name);
    changed(record.id);
    runner_.notify();
  }
  res.set_header("Location", "/v1/jobs/" + record.id);
  send_json(
      res, created ? 201 : 200,
      {{"id", record.id}, {"status", to_string(record.status)}, {"links", job_links(record.id)}});
}

void Api::list(const httplib::Request& req, httplib::Response& res) {
  std::optional<JobStatus> status;
  if (req.has_param("status")) {
    status = job_status_from_string(req.get_param_value("status"));
    if (!status)
      return send_error(res, 400, "invalid_parameter",
                        "status must be one of queued, running, succeeded, failed, cancelled");
  }
  long long limit = 50, offset = 0;
  if (req.has_param("limit") && !parse_int(req.get_param_value("limit"), 1, 1000, limit))
    return send_error(res, 400, "invalid_parameter", "limit must be an integer in 1..1000");
  if (req.has_param("offset") && !parse_int(req.get_param_value("offset"), 0, 1000000000, offset))
    return send_error(res, 400, "invalid_parameter", "offset must be a non-negative integer");
  const std::string name = req.has_param("name") ? req.get_param_value("name") : "";
  if (name.size() > 200)
    return send_error(res, 400, "invalid_parameter", "name is longer than 200 characters");
  json jobs = json::array();
  for (const JobRecord& r :
       store_.list(status, static_cast<int>(limit), static_cast<int>(offset), name))
    jobs.push_back(view(r));
  send_json(res, 200,
            {{"jobs", jobs},
             {"total", store_.count(status, name)},
             {"limit", limit},
             {"offset", offset}});
}

void Api::cancel(const std::string& id, httplib::Response& res) {
  const auto before = store_.get(id);
  if (!before) return send_error(res, 404, "not_found", "no job " + id);
  const auto finished = [&](JobStatus s) {
    send_error(res, 409, "conflict",
               "job " + id + " has already " +
                   (s == JobStatus::cancelled ? std::string("been cancelled")
                                              : std::string(to_string(s))));
  };
  // Finished, with its results held in memory: a succeeded one is cancelled (they are dropped).
  if (const std::optional<JobStatus> held = runner_.cancel_unstored(id)) {
    if (*held != JobStatus::succeeded) return finished(*held);
    spdlog::info("job {}: cancelled; its results, held in memory, are dropped", id);
    return send_json(res, 202, view(*before));
  }
  if (is_terminal(before->status)) return finished(before->status);
  std::optional<JobRecord> after;
  try {
    after = store_.request_cancel(id);
    runner_.store_wrote();
  } catch (const StoreError& e) {
    if (!e.transient()) throw;
    // Applied in memory (a running job stops after its iteration), recorded when the store
    // writes again, before any job is claimed.
    runner_.store_failed(e);
    runner_.defer_cancel(id);
    after = before;
  }
  runner_.interrupt(id);  // a running job stops before its next pack
  spdlog::info("job {}: cancel requested ({})", id, to_string(after->status));
  changed(id);
  send_json(res, 202, view(*after));
}

void Api::changed(const std::string& id) noexcept {
  try {
    const std::optional<JobRecord> r = store_.get(id);
    if (!r || r->status != JobStatus::running) {
      // Its partial results are of no more use (a finished job serves its stored files).
      std::lock_guard<std::mutex> lock(partial_mutex_);
      partial_.erase(id);
    }
    if (r)
      hub_.publish("job", id, encode(view(*r)));
    else
      hub_.publish("deleted", id, encode(json{{"id", id}}));
  } catch (const std::exception& e) {
    spdlog::warn("job {}: no live update sent: {}", id, e.what());
  }
}

// Server-sent events: `job` with a job's view each time it changes (queued, started, each
// iteration, finished, cancelled), `deleted` when it is gone; a comment after 15 s without one
// keeps the connection alive; a closed page's stream ends within a quarter of a second. With `job`
// (/v1/jobs/{id}/events, /v1/events?job=ID): that job's only. Each stream holds one of the server's
// connection threads, so at most --max-event-streams are open at once; more are answered 503. One
// client address may hold at most half of its --max-connections-per-client in streams, and one
// other than loopback at most --max-event-streams-per-client (429 past either), so that one
// client cannot take them all nor lock itself out; without a token the service is on loopback,
// where every local page shares one address, and a page of another origin gets no stream (403
// cross_origin: an EventSource of a foreign page would hold a slot).
void Api::events(const httplib::Request& req, const std::string& job, httplib::Response& res) {
  if (!opt_.token && cross_origin(req)) {
    const std::string origin = req.get_header_value("Origin");
    return send_error(res, 403, "cross_origin",
                      "an event stream for a page of another origin (" +
                          (origin.empty() ? std::string("a cross-site page") : origin) +
                          ") is refused: only the service's own dashboard may hold one");
  }
  // Each stream holds one of its address's --max-connections-per-client connections: an address
  // holds at most half of them in streams, so that its other requests (/healthz, the API) still
  // get through (16 streams from one address locked it out). Loopback, where every local page
  // shares the address, has only that cap; other addresses also --max-event-streams-per-client.
  const std::size_t half =
      static_cast<std::size_t>(std::max(opt_.max_connections_per_client / 2, 1));
  const bool local = loopback_address(req.remote_addr);
  const std::size_t cap =
      local || hub_.max_per_client() == 0 ? half : std::min(half, hub_.max_per_client());
  EventHub::Refused why = EventHub::Refused::full;
  std::optional<EventHub::Stream> stream = hub_.open(req.remote_addr, &why, cap);
  if (!stream && why == EventHub::Refused::client_full) {
    res.set_header("Retry-After", "10");
    return send_error(res, 429, "too_many_streams",
                      "this client has " + std::to_string(cap) +
                          " event streams open, the most one client address may (half of "
                          "--max-connections-per-client" +
                          (local ? std::string() : ", and --max-event-streams-per-client") +
                          "): close a page, or reload it later",
                      json{{"limit", cap}});
  }
  if (!stream) {
    res.set_header("Retry-After", "10");
    return send_error(res, 503, "too_many_streams",
                      "the server has " + std::to_string(hub_.max_streams()) +
                          " event streams open, the most it serves (--max-event-streams, at most "
                          "half of --max-connections): close a page, or reload it later",
                      json{{"limit", hub_.max_streams()}});
  }
  // A stream for a job that does not exist (?job=) would hold a slot for nothing. Checked once
  // the stream is open, so that a deletion in between is either seen here or sent to it.
  if ((req.has_param("job") || !job.empty()) && !store_.get(job))
    return send_error(res, 404, "not_found", "no job " + job);
  struct State {
    EventHub::Stream stream;
    std::string job;
    bool started = false;
  };
  auto state = std::make_shared<State>(State{std::move(*stream), job});
  res.set_header("Cache-Control", "no-store");
  res.set_chunked_content_provider(
      "text/event-stream", [state](std::size_t, httplib::DataSink& sink) {
        std::string out;
        if (!state->started) {
          state->started = true;
          out = "retry: 3000\n: ftctune events\n\n";
        } else {
          // Waits in short slices, so that a page closed meanwhile frees its stream (and its
          // connection thread) at once; a comment after 15 s without an event keeps proxies
          // from closing the connection.
          for (int slice = 0; slice < 60 && out.empty(); ++slice) {
            const std::optional<std::vector<Event>> events = state->stream.next(250);
            if (!events) {
              sink.done();
              return true;
            }
            bool gone = false;
            for (const Event& e : *events)
              if (state->job.empty() || e.job_id == state->job) {
                out += e.text;
                // A job's own stream ends with its deletion: nothing more will come.
                gone = gone || (!state->job.empty() && e.text.find("\nevent: deleted\n") !=
                                                           std::string::npos);
              }
            if (gone) {
              if (!sink.write(out.data(), out.size())) return false;
              sink.done();
              return true;
            }
            if (out.empty() && GuardedServer::peer_closed()) return false;
          }
          if (out.empty()) out = ":\n\n";
        }
        return sink.write(out.data(), out.size());
      });
}

// The partial results of a running job, from its last checkpoint: history and trials as they
// stand, and gains.json for its best so far as its trial recorded it (nothing is simulated in a
// request). Each is made at most once per checkpoint: kept per running job until its next
// iteration, made by one request at a time per job (the others of that job wait for it, then
// take what it made; other jobs' requests do not), and dropped once the job stops running.
void Api::running_result(const httplib::Request& req, httplib::Response& res, const JobRecord& job,
                         const std::string& what) {
  const std::string& id = job.id;
  const std::string format = req.has_param("format") ? req.get_param_value("format") : "";
  if (what == "comparison" || what == "report")
    return send_error(res, 409, "not_ready",
                      "job " + id + " is running; its " + what +
                          " exists once it has finished (its gains, history and trials so far "
                          "are served now)");
  if (what == "history" && !format.empty() && format != "csv" && format != "json")
    return send_error(res, 400, "invalid_parameter", "format must be csv or json");
  const bool gains = what == "gains";
  // What is kept for the job, if it is of its latest checkpoint (the record's iteration, written
  // with it) and has what is asked for.
  const auto kept = [&]() -> std::shared_ptr<const PartialResults> {
    std::lock_guard<std::mutex> lock(partial_mutex_);
    const auto it = partial_.find(id);
    if (it == partial_.end() || it->second->iteration < job.iteration ||
        (gains && !it->second->gains))
      return nullptr;
    return it->second;
  };
  std::shared_ptr<const PartialResults> p = kept();
  if (!p) {
    const std::shared_ptr<std::mutex> job_mutex = making_mutex(id);
    std::lock_guard<std::mutex> making(*job_mutex);
    p = kept();  // made by the request this one waited for
    if (!p) {
      const std::optional<JobStore::Checkpoint> c = store_.checkpoint_with_trials(id);
      if (!c)
        return send_error(res, 409, "not_ready",
                          "job " + id + " has not finished its first iteration yet");
      auto made = std::make_shared<PartialResults>();
      {
        std::lock_guard<std::mutex> lock(partial_mutex_);
        const auto it = partial_.find(id);
        if (it != partial_.end() && it->second->iteration == c->iteration) *made = *it->second;
      }
      made->iteration = c->iteration;
      if (made->trials.empty() || (gains && !made->gains)) {
        TuningOutcome r = outcome_of(id, *c);
        made->trials = trials_csv(r);
        made->history = history_csv(r);
        made->history_rows = encode(history_rows(r));
        // The best so far as the run stored it: nothing is simulated in a request (a
        // comparison here took seconds per heavy job and held a server thread meanwhile).
        if (gains) made->gains = gains_document(r).dump(2) + "\n";
      }
      p = made;
      std::lock_guard<std::mutex> lock(partial_mutex_);
      partial_[id] = p;
      // Only running jobs are kept (changed() drops the others); at most as many as can run,
      // whatever a race with a job's end left.
      if (partial_.size() > static_cast<std::size_t>(std::max(opt_.concurrent_jobs, 1)) + 1)
        for (auto it = partial_.begin(); it != partial_.end();)
          it = it->first == id ? std::next(it) : partial_.erase(it);
    }
  }
  res.set_header("Ftctune-Partial", "true");
  if (gains) return res.set_content(*p->gains, "application/json");
  if (what == "trials") return res.set_content(p->trials, "text/csv");
  if (format == "json") return res.set_content(p->history_rows, "application/json");
  res.set_content(p->history, "text/csv");
}

std::shared_ptr<std::mutex> Api::making_mutex(const std::string& id) {
  std::lock_guard<std::mutex> lock(partial_mutex_);
  for (auto it = making_.begin(); it != making_.end();)
    it = it->first != id && it->second.expired() ? making_.erase(it) : std::next(it);
  std::shared_ptr<std::mutex> m = making_[id].lock();
  if (!m) {
    m = std::make_shared<std::mutex>();
    making_[id] = m;
  }
  return m;
}

TuningOutcome Api::outcome_of(const std::string& id, const JobStore::Checkpoint& c) {
  const Job job = parse_job_text(store_.job_json(id), "job " + id);
  json trials = json::array();
  for (const std::string& rows : c.trials)
    for (json& t : json::parse(rows)) trials.push_back(std::move(t));
  return checkpoint_outcome(
      job, json{{"optimizer", json::parse(c.optimizer)}, {"trials", std::move(trials)}});
}

// Every stored file of a finished job with results (a listing without `name`), by name: the
// folder `ftctune run` writes, and report.html once drawn.
void Api::files(const std::string& id, const std::string& name, httplib::Response& res) {
  const auto job = store_.get(id);
  if (!job) return send_error(res, 404, "not_found", "no job " + id);
  const std::map<std::string, std::uint64_t> sizes = store_.artifact_sizes(id);
  if (sizes.empty())
    return send_error(res, 409, "not_ready",
                      "job " + id + " is " + to_string(job->status) +
                          "; its files exist once it has succeeded, or been cancelled after an "
                          "iteration");
  const bool partial = job->status == JobStatus::cancelled;
  if (partial) res.set_header("Ftctune-Partial", "true");
  if (name.empty()) {
    json list = json::array();
    for (const auto& [n, bytes] : sizes) list.push_back({{"name", n}, {"bytes", bytes}});
    return send_json(res, 200, {{"id", id}, {"partial", partial}, {"files", list}});
  }
  const std::optional<std::string> content = store_.artifact(id, name);
  if (!content) return send_error(res, 404, "not_found", "job " + id + " has no file " + name);
  res.set_content(*content, media_type(name));
}

void Api::result(const httplib::Request& req, httplib::Response& res, const std::string& id,
                 const std::string& what) {
  const auto job = store_.get(id);
  if (!job) return send_error(res, 404, "not_found", "no job " + id);
  // Another point of a front: of a finished run only (a running job's front is not final, and
  // its best so far is no point of it).
  if (what == "gains" && req.has_param("pick") && job->status != JobStatus::succeeded)
    return send_error(res, 409, "not_ready",
                      "pick: job " + id + " is " + to_string(job->status) +
                          "; a point of its front can be picked once it has succeeded");
  if (job->status == JobStatus::running) {
    if (runner_.unstored(id))
      return send_error(res, 409, "not_ready",
                        "job " + id +
                            " has finished; its results wait in the server's memory until the "
                            "store can write them");
    return running_result(req, res, *job, what);
  }
  // A cancelled job that ran an iteration keeps its results so far, marked partial.
  const bool partial =
      job->status == JobStatus::cancelled && store_.artifact_sizes(id).count("gains.json");
  if (job->status != JobStatus::succeeded && !partial)
    return send_error(res, 409, "not_ready",
                      "job " + id + " is " + to_string(job->status) +
                          (job->status == JobStatus::cancelled
                               ? "; it was cancelled before it finished an iteration, so it has no "
                                 "results"
                               : "; its results exist once it has succeeded (a running job's "
                                 "gains, history and trials so far are served)"));
  if (partial) res.set_header("Ftctune-Partial", "true");
  const std::string format = req.has_param("format") ? req.get_param_value("format") : "";
  if (what == "gains" && req.has_param("pick")) {
    // Another point of the front, as `ftctune pick RUN --rule RULE` writes its gains file.
    const std::string rule = req.get_param_value("pick");
    if (!store_.artifact_sizes(id).count("front.json"))
      return send_error(
          res, 400, "invalid_parameter",
          "pick: job " + id + " has no front (a job with two or more soft goals has one)");
    try {
      // What pick_gains reads, not the trajectories.
      const RunDirectory dir(store_, id, {"front.json", "job.json", "gains.json", "trials.csv"});
      return send_json(res, 200, pick_gains(dir.path, rule));
    } catch (const InputError& e) {
      // The rule's own message, never the temporary directory's file names.
      return send_error(
          res, 400, "invalid_parameter",
          "pick=" + rule + ": " +
              (e.errors().empty() ? std::string(e.what()) : e.errors().front().message));
    }
  } else if (what == "gains") {
    res.set_content(store_.artifact(id, "gains.json").value_or(""), "application/json");
  } else if (what == "report") {
    res.set_content(report(id), "text/html; charset=utf-8");
  } else if (what == "trials") {
    res.set_content(store_.artifact(id, "trials.csv").value_or(""), "text/csv");
  } else if (what == "history") {
    if (format == "json") {
      const json gains = json::parse(store_.artifact(id, "gains.json").value_or("{}"));
      send_json(res, 200, gains.value("history", json::array()));
    } else if (format.empty() || format == "csv") {
      res.set_content(store_.artifact(id, "history.csv").value_or(""), "text/csv");
    } else {
      return send_error(res, 400, "invalid_parameter", "format must be csv or json");
    }
  } else {
    if (format == "md")
      res.set_content(store_.artifact(id, "comparison.md").value_or(""), "text/markdown");
    else if (format.empty() || format == "json")
      res.set_content(store_.artifact(id, "comparison.json").value_or(""), "application/json");
    else
      return send_error(res, 400, "invalid_parameter", "format must be json or md");
  }
}

// The front of a succeeded job evaluated on held-out members (issue 42), as `ftctune evaluate JOB
// --front RUN --count N --seed S` writes its front.json: each point's goals held out beside its
// in-sample ones (`in_sample`), the held-out knee, the compared controllers. count: 1..1 000 000
// (default the ensemble's); seed: default the ensemble's + 1, as evaluate's. Priced like a job
// (the points and compared controllers on every member, within the server's step budget), run
// on the request's thread, and kept: the latest one per job (held-out.json), served again while
// its seed and count are asked for.
void Api::held_out(const httplib::Request& req, httplib::Response& res, const std::string& id) {
  const auto record = store_.get(id);
  if (!record) return send_error(res, 404, "not_found", "no job " + id);
  if (record->status != JobStatus::succeeded)
    return send_error(res, 409, "conflict",
                      "job " + id + " is " + std::string(to_string(record->status)) +
                          ": its front is evaluated held out once it has succeeded");
  if (!store_.artifact_sizes(id).count("front.json"))
    return send_error(
        res, 400, "invalid_parameter",
        "held-out: job " + id + " has no front (a job with two or more soft goals has one)");
  const Job job = parse_job(json::parse(store_.job_json(id)), "job " + id);
  if (!job.ensemble)
    return send_error(res, 400, "invalid_parameter",
                      "held-out: job " + id +
                          " has no ensemble: it was tuned on all of its scenarios, so there are "
                          "no other members to draw (a job with an ensemble has them)");
  const auto number = [&](const char* key, std::uint64_t lo, std::uint64_t hi,
                          std::uint64_t fallback) -> std::optional<std::uint64_t> {
    if (!req.has_param(key)) return fallback;
    const std::string v = req.get_param_value(key);
    std::uint64_t n = 0;
    const auto [end, ec] = std::from_chars(v.data(), v.data() + v.size(), n);
    if (ec != std::errc() || end != v.data() + v.size() || n < lo || n > hi) {
      send_error(res, 400, "invalid_parameter",
                 std::string(key) + " must be an integer in [" + std::to_string(lo) + ", " +
                     std::to_string(hi) + "], got \"" + v + "\"");
      return std::nullopt;
    }
    return n;
  };
  const auto count = number("count", 1, 1000000, static_cast<std::uint64_t>(job.ensemble->count));
  if (!count) return;
  const auto seed =
      number("seed", 0, std::numeric_limits<std::uint64_t>::max(), job.ensemble->seed + 1);
  if (!seed) return;
  // The price: every point and compared controller (and the job's own) on every held-out member
  // and listed scenario, at the job's cost of a scenario.
  const json stored = json::parse(store_.artifact(id, "front.json").value_or("{}"));
  const double evaluations =
      static_cast<double>(stored.value("points", json::array()).size() + job.compare.size() + 1);
  const double per_scenario = job.step_cost_per_evaluation() /
                              static_cast<double>(std::max<std::size_t>(1, job.scenario_count()));
  const double steps =
      evaluations * per_scenario * static_cast<double>(*count + job.scenarios.size());
  if (steps > opt_.max_steps)
    return send_error(
        res, 400, "job_too_large",
        "held-out: " + fmt_g(evaluations) + " controllers on " + std::to_string(*count) +
            " members need " + fmt_g(steps) + " simulated steps, " + fmt_g(steps / opt_.max_steps) +
            " times the server's budget of " + fmt_g(opt_.max_steps) + ": ask for fewer members",
        json{{{"steps", steps}, {"budget", opt_.max_steps}}});
  if (const auto kept = store_.artifact(id, "held-out.json")) {
    const json k = json::parse(*kept);
    if (k["held_out"].value("seed", std::uint64_t{0}) == *seed &&
        k["held_out"].value("count", std::uint64_t{0}) == *count)
      return res.set_content(*kept, "application/json");
  }
  const RunDirectory dir(store_, id, {"front.json", "job.json", "gains.json", "trials.csv"});
  EvaluateJobOptions o;
  o.front = dir.path;
  o.count = static_cast<std::int64_t>(*count);
  o.seed = *seed;
  o.out = dir.path / "held-out";
  o.threads = opt_.threads;
  o.figure = false;
  EvaluateJobResult r;
  try {
    r = evaluate_job(job, o);
  } catch (const InputError& e) {
    // The message only: a file name would be the server's temporary directory's.
    return send_error(
        res, 400, "invalid_parameter",
        "held-out: " + (e.errors().empty() ? std::string(e.what()) : e.errors().front().message));
  }
  json doc = json::parse(read_file(r.out / "front.json").value_or("{}"));
  doc["held_out"]["run"] = "job " + id;  // not the server's temporary directory
  const std::string text = doc.dump(2) + "\n";
  keep(id, "held-out.json", text);
  res.set_content(text, "application/json");
}

void Api::keep(const std::string& id, const std::string& name, const std::string& content) {
  try {
    store_.put_artifact(id, name, content);
    runner_.store_wrote();
  } catch (const StoreError& e) {
    // Served all the same; made again on the next request.
    if (e.transient()) runner_.store_failed(e);
    spdlog::warn("job {}: {} not kept: {}", id, name, e.what());
  }
}

// report.html of a succeeded (or cancelled, partial) job: drawn from its stored files on first
// request, then kept.
std::string Api::report(const std::string& id) {
  if (auto cached = store_.artifact(id, "report.html")) return *cached;
  const RunDirectory dir(store_, id);
  const ReportResult r = render_report(dir.path, ReportOptions{});
  const std::string html = read_file(r.html).value_or("");
  keep(id, "report.html", html);
  return html;
}

bool Api::same_origin(const httplib::Request& req, httplib::Response& res) const {
  // Headers the checks below read must be unambiguous (RFC 9112 §3.2 and §5.1: a server
  // answers 400 to more than one Host, and to white space between a field name and its colon).
  if (req.get_header_value_count("Host") > 1) {
    send_error(res, 400, "bad_request", "the request has more than one Host header");
    return false;
  }
  for (const auto& [name, value] : req.headers)
    if (name.empty() || name.find_first_of(" \t") != std::string::npos) {
      send_error(res, 400, "bad_request",
                 "a header field name holds white space (\"" + name.substr(0, 64) +
                     "\"): none may stand before its colon");
      return false;
    }
  // With a token, a page of another site cannot send it (it is a header, and no CORS header
  // lets another origin's script add one); the checks are for the service without one, on a
  // loopback address.
  if (opt_.token) return true;
  const std::string host = req.get_header_value("Host");
  if (!host.empty() && !loopback_host(host_name(host), opt_.bind)) {
    send_error(res, 403, "forbidden_host",
               "the Host header names " + host_name(host) +
                   ", not this machine's loopback (localhost, 127.0.0.1, [::1]): a page of "
                   "another site reached the service through its own name (DNS rebinding), or "
                   "it is behind a proxy, which needs --token");
    return false;
  }
  // A request that changes something, sent by a page: it must be the dashboard's own.
  const std::string& m = req.method;
  if (m == "GET" || m == "HEAD" || m == "OPTIONS") return true;
  const std::string origin = req.get_header_value("Origin");
  if (cross_origin(req)) {
    send_error(res, 403, "cross_origin",
               "a " + m + " from a page of another origin (" +
                   (origin.empty() ? std::string("a cross-site page") : origin) +
                   ") is refused: only the service's own dashboard may change its jobs");
    return false;
  }
  return true;
}

bool Api::authenticate(const httplib::Request& req, httplib::Response& res) const {
  if (!same_origin(req, res)) return false;
  if (authorised(req)) return true;
  res.set_header("WWW-Authenticate", "Bearer");
  send_error(res, 401, "unauthorized",
             "a valid \"Authorization: Bearer <token>\" header is required");
  return false;
}

// Bodies are read here, not by the library: it holds a chunked body (no Content-Length) in
// memory whole before any limit applies, so a 300 MB chunked POST took 600 MB. This keeps at
// most the limit, chunked or not (a declared Content-Length above it the library reads past
// without keeping, then fails the read).
void Api::receive(const httplib::Request& req, httplib::Response& res,
                  const httplib::ContentReader& read) {
  // Form uploads are not part of the API (and the library cannot hand their parts to one
  // receiver).
  if (req.is_multipart_form_data()) {
    send_error(res, 415, "unsupported_media_type", "send the job as application/json");
    return;
  }
  httplib::Request r = req;
  bool too_large = false;
  std::size_t dropped = 0;
  // Past the limit the rest is read and dropped, not kept: closing on unread bytes would
  // reset the connection, and the client would lose the 413 that says why. Up to a point: a
  // client that keeps sending past 8 MiB more is cut off (and may not see the answer).
  constexpr std::size_t kMaxDropped = 8u << 20;
  const bool complete = read([&](const char* data, std::size_t n) {
    too_large = too_large || r.body.size() + n > opt_.max_body_bytes;
    if (!too_large)
      r.body.append(data, n);
    else
      dropped += n;
    return dropped <= kMaxDropped;
  });
  // The library reads nothing of a body whose Content-Length is above the limit.
  if (!complete && req.has_header("Content-Length")) {
    const std::string length = req.get_header_value("Content-Length");
    std::uint64_t n = 0;
    const auto [end, ec] = std::from_chars(length.data(), length.data() + length.size(), n);
    too_large =
        ec == std::errc::result_out_of_range || (ec == std::errc() && n > opt_.max_body_bytes);
  }
  if (!complete && !too_large) {
    if (GuardedServer::request_timed_out()) {
      res.set_header("Connection", "close");
      send_error(res, 408, "request_timeout",
                 "the request body did not arrive within " + seconds_text(opt_.body_timeout) +
                     " of its headers");
      return;
    }
    send_error(res, 400, "bad_request", "the request body could not be read");
    return;
  }
  if (too_large) {
    if (!complete) res.set_header("Connection", "close");
    send_error(res, 413, "payload_too_large", "the request body exceeds the server's limit");
    return;
  }
  dispatch(r, res);
}

void Api::handle(const httplib::Request& req, httplib::Response& res,
                 const httplib::ContentReader* body) {
  if (web_asset(req.path) ? !same_origin(req, res) : !authenticate(req, res)) return;
  if (body)
    receive(req, res, *body);
  else
    dispatch(req, res);
}

void Api::configure(httplib::Server& http) {
  const auto handler = [this](const httplib::Request& req, httplib::Response& res) {
    dispatch(req, res);
  };
  const auto with_body = [this](const httplib::Request& req, httplib::Response& res,
                                const httplib::ContentReader& read) { receive(req, res, read); };
  // One catch-all route per method: dispatch() tells 404 (no such resource) from 405.
  http.Get(".*", handler);
  http.Post(".*", with_body);
  http.Put(".*", with_body);
  http.Patch(".*", with_body);
  http.Delete(".*", with_body);
  http.Options(".*", handler);
  http.set_pre_routing_handler([this](const httplib::Request& req, httplib::Response& res) {
    return (web_asset(req.path) ? same_origin(req, res) : authenticate(req, res))
               ? httplib::Server::HandlerResponse::Unhandled
               : httplib::Server::HandlerResponse::Handled;
  });
  // Every answer: no type sniffing, no referrer, and a content policy (no CORS header is ever
  // sent, so other origins' pages cannot read the API).
  http.set_post_routing_handler([](const httplib::Request& req, httplib::Response& res) {
    res.set_header("X-Content-Type-Options", "nosniff");
    res.set_header("Referrer-Policy", "no-referrer");
    // Job data stays out of the browser's and any proxy's cache.
    if (req.path.rfind("/v1/", 0) == 0) res.set_header("Cache-Control", "no-store");
    const char* policy = web_asset(req.path) ? kPagePolicy : kDataPolicy;
    if (res.get_header_value("Content-Type").rfind("text/html", 0) == 0 && !web_asset(req.path))
      policy = kReportPolicy;
    res.set_header("Content-Security-Policy", policy);
  });
  // Errors the library produces itself (413 above the body limit, 400 for a malformed
  // request, 404 for an unknown method) get the same JSON body as ours.
  http.set_error_handler([this](const httplib::Request&, httplib::Response& res) {
    if (!res.body.empty()) return;
    // The parser's 400 for a request whose reading ran out of time.
    if (res.status == 400 && GuardedServer::request_timed_out())
      send_error(res, 408, "request_timeout",
                 "the request did not arrive in time (its headers are due within " +
                     seconds_text(opt_.header_timeout) + " of its first byte, its body within " +
                     seconds_text(opt_.body_timeout) + " of its headers)");
    else if (res.status == 413)
      send_error(res, 413, "payload_too_large", "the request body exceeds the server's limit");
    else
      send_error(res, res.status, "http_error", "HTTP status " + std::to_string(res.status));
  });
  http.set_exception_handler(
      [this](const httplib::Request&, httplib::Response& res, std::exception_ptr ep) {
        std::string what = "unknown error";
        try {
          std::rethrow_exception(ep);
        } catch (const StoreError& e) {
          if (e.transient()) {
            runner_.store_failed(e);
            return insufficient_storage(res, e.what());
          }
          what = e.what();
        } catch (const std::filesystem::filesystem_error& e) {
          // A report drawn in a temporary directory on a full disk.
          if (e.code() == std::errc::no_space_on_device || e.code().value() == EDQUOT) {
            res.set_header("Retry-After", "60");
            return send_error(res, 507, "insufficient_storage", e.what());
          }
          what = e.what();
        } catch (const std::bad_alloc&) {
          // An allocation the machine could not give: a clean answer, never an abort.
          spdlog::error("request failed: out of memory");
          return send_error(res, 500, "out_of_memory",
                            "the server ran out of memory serving this request");
        } catch (const std::exception& e) {
          what = e.what();
        } catch (...) {
        }
        spdlog::error("request failed: {}", what);
        send_error(res, 500, "internal_error", what);
      });
  http.set_payload_max_length(opt_.max_body_bytes);
}

}  // namespace ftc::tune::service_detail
