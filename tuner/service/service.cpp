#include "ftc/tune/service/service.hpp"

#include <openssl/crypto.h>
#include <spdlog/spdlog.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstdio>
#include <fstream>
#include <mutex>
#include <sstream>
#include <thread>

#include "ftc/tune/io/files.hpp"
#include "service/httplib.hpp"
#include "ftc/tune/job/job.hpp"
#include "ftc/tune/service/job_store.hpp"
#include "ftc/tune/report/report.hpp"
#include "ftc/tune/evaluators/tbb_evaluator.hpp"
#include "ftc/tune/run/documents.hpp"
#include "ftc/tune/run/tuning_run.hpp"
#include "ftc/version.hpp"
#include "ftc/runtime/json_reader.hpp"

namespace ftc::tune {

using nlohmann::json;

bool is_loopback(const std::string& host) {
  return host == "localhost" || host == "::1" || host.rfind("127.", 0) == 0;
}

std::vector<FieldError> ServiceOptions::validate() const {
  std::vector<FieldError> errs;
  if (!is_loopback(bind) && !token)
    errs.push_back({"--bind", "refusing to listen on " + bind +
                                  " (not loopback) without --token-file: anyone who can reach it "
                                  "could submit jobs"});
  if (port < 0 || port > 65535) errs.push_back({"--port", "must be in 0..65535"});
  if (concurrent_jobs < 1 || concurrent_jobs > 64)
    errs.push_back({"--concurrent-jobs", "must be in 1..64"});
  if (token && token->empty()) errs.push_back({"--token-file", "the token is empty"});
  if (max_body_bytes < 1024) errs.push_back({"--max-body-kib", "must be at least 1 KiB"});
  if (!(max_steps > 0)) errs.push_back({"--max-steps", "must be > 0"});
  return errs;
}

namespace {

void send_error(httplib::Response& res, int status, const std::string& code,
                const std::string& message, json details = json::array()) {
  res.status = status;
  res.set_content(
      json{{"error", {{"code", code}, {"message", message}, {"details", details}}}}.dump(),
      "application/json");
}

void send_json(httplib::Response& res, int status, const json& body) {
  res.status = status;
  res.set_content(body.dump(), "application/json");
}

json nullable(const std::string& s) { return s.empty() ? json(nullptr) : json(s); }

json job_links(const std::string& id) {
  const std::string base = "/v1/jobs/" + id;
  return {{"self", base},
          {"gains", base + "/gains"},
          {"history", base + "/history"},
          {"comparison", base + "/comparison"},
          {"report", base + "/report"},
          {"cancel", base + "/cancel"}};
}

json job_json_view(const JobRecord& r) {
  json progress = {{"iteration", r.iteration >= 0 ? json(r.iteration) : json(nullptr)},
                   {"iterations", r.iterations},
                   {"evaluations", r.evaluations},
                   {"total_evaluations", r.total_evaluations},
                   {"best_fitness", r.best_fitness ? json(*r.best_fitness) : json(nullptr)},
                   {"best", r.best}};
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
          {"links", job_links(r.id)}};
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

}  // namespace

struct TuningService::Impl {
  ServiceOptions opt;
  JobStore store;
  httplib::Server http;
  std::thread listener;
  std::vector<std::thread> workers;
  std::atomic<bool> stopping{false};
  std::mutex wake_mutex;
  std::condition_variable wake;
  std::uint64_t submissions = 0;  // bumped under wake_mutex on every submission
  int recovered = 0;
  bool started = false;
  std::atomic<int> report_counter{0};

  explicit Impl(ServiceOptions o) : opt(std::move(o)), store(opt.store) {}

  // ---- HTTP ------------------------------------------------------------------------------------

  bool authorised(const httplib::Request& req) const {
    if (!opt.token) return true;
    const std::string expected = "Bearer " + *opt.token;
    const std::string got = req.get_header_value("Authorization");
    // Constant time in the token's content; only the length can leak.
    return got.size() == expected.size() &&
           CRYPTO_memcmp(got.data(), expected.data(), got.size()) == 0;
  }

  void method_not_allowed(httplib::Response& res, const char* allow) {
    res.set_header("Allow", allow);
    send_error(res, 405, "method_not_allowed", std::string("this resource allows ") + allow);
  }

  void dispatch(const httplib::Request& req, httplib::Response& res) {
    const std::vector<std::string> p = split_path(req.path);
    const std::string& m = req.method;
    if (p.size() == 1 && p[0] == "healthz") {
      if (m != "GET") return method_not_allowed(res, "GET");
      return send_json(res, 200,
                       {{"status", "ok"},
                        {"version", kVersion},
                        {"queued", store.count(JobStatus::queued)},
                        {"running", store.count(JobStatus::running)}});
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
      if (m != "GET") return method_not_allowed(res, "GET");
      const auto job = store.get(id);
      if (!job) return send_error(res, 404, "not_found", "no job " + id);
      return send_json(res, 200, job_json_view(*job));
    }
    if (p.size() == 4 && p[3] == "cancel") {
      if (m != "POST") return method_not_allowed(res, "POST");
      return cancel(id, res);
    }
    if (p.size() == 4 &&
        (p[3] == "gains" || p[3] == "history" || p[3] == "comparison" || p[3] == "report")) {
      if (m != "GET") return method_not_allowed(res, "GET");
      return result(req, res, id, p[3]);
    }
    send_error(res, 404, "not_found", "no such resource: " + req.path);
  }

  void submit(const httplib::Request& req, httplib::Response& res) {
    const auto bad_request = [&](const char* code, const InputError& e) {
      json details = json::array();
      for (const FieldError& fe : e.errors())
        details.push_back({{"path", fe.path}, {"message", fe.message}});
      send_error(res, 400, code, e.what(), details);
    };
    json body;
    try {
      body = json_io::parse_json_text(req.body, "request body");
    } catch (const InputError& e) {
      return bad_request("invalid_json", e);
    }
    Job job;
    try {
      job = parse_job(body, "request body");
    } catch (const InputError& e) {
      return bad_request("invalid_job", e);
    }
    if (!job.tuning)
      return send_error(res, 400, "invalid_job", "request body: /tuning: is required to tune",
                        json::array({{{"path", "/tuning"}, {"message", "is required to tune"}}}));
    const double steps = static_cast<double>(job.tuning->algorithm->evaluations()) *
                         static_cast<double>(job.steps_per_evaluation());
    if (steps > opt.max_steps)
      return send_error(res, 400, "job_too_large",
                        "the job needs " + fmt_g(steps) +
                            " simulated steps (evaluations x steps per "
                            "evaluation), " +
                            fmt_g(steps / opt.max_steps) + " times the server's budget of " +
                            fmt_g(opt.max_steps),
                        json{{{"steps", steps}, {"budget", opt.max_steps}}});

    Submission s;
    s.job_json = to_json(job).dump();
    s.name = job.name;
    s.iterations = job.tuning->algorithm->iterations();
    s.total_evaluations = job.tuning->algorithm->evaluations();
    const std::string key = req.get_header_value("Idempotency-Key");
    if (!key.empty()) {
      if (key.size() > 200)
        return send_error(res, 400, "invalid_header",
                          "Idempotency-Key is longer than 200 characters");
      s.idempotency_key = key;
    }
    const auto [record, created] = store.submit(s);
    if (!created && store.job_json(record.id) != s.job_json)
      return send_error(
          res, 409, "idempotency_conflict",
          "Idempotency-Key was already used for job " + record.id + " with a different job");
    if (created) {
      spdlog::info("job {} ({}) queued", record.id, record.name);
      {
        std::lock_guard<std::mutex> lock(wake_mutex);
        ++submissions;
      }
      wake.notify_one();
    }
    res.set_header("Location", "/v1/jobs/" + record.id);
    send_json(
        res, created ? 201 : 200,
        {{"id", record.id}, {"status", to_string(record.status)}, {"links", job_links(record.id)}});
  }

  void list(const httplib::Request& req, httplib::Response& res) {
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
    json jobs = json::array();
    for (const JobRecord& r : store.list(status, static_cast<int>(limit), static_cast<int>(offset)))
      jobs.push_back(job_json_view(r));
    send_json(
        res, 200,
        {{"jobs", jobs}, {"total", store.count(status)}, {"limit", limit}, {"offset", offset}});
  }

  void cancel(const std::string& id, httplib::Response& res) {
    const auto before = store.get(id);
    if (!before) return send_error(res, 404, "not_found", "no job " + id);
    if (is_terminal(before->status))
      return send_error(
          res, 409, "conflict",
          "job " + id + " has already " +
              (before->status == JobStatus::cancelled ? std::string("been cancelled")
                                                      : std::string(to_string(before->status))));
    const auto after = store.request_cancel(id);
    spdlog::info("job {}: cancel requested ({})", id, to_string(after->status));
    send_json(res, 202, job_json_view(*after));
  }

  void result(const httplib::Request& req, httplib::Response& res, const std::string& id,
              const std::string& what) {
    const auto job = store.get(id);
    if (!job) return send_error(res, 404, "not_found", "no job " + id);
    if (job->status != JobStatus::succeeded)
      return send_error(res, 409, "not_ready",
                        "job " + id + " is " + to_string(job->status) +
                            "; its results exist once it has succeeded");
    const std::string format = req.has_param("format") ? req.get_param_value("format") : "";
    if (what == "gains") {
      res.set_content(store.artifact(id, "gains.json").value_or(""), "application/json");
    } else if (what == "report") {
      res.set_content(report(id), "text/html; charset=utf-8");
    } else if (what == "history") {
      if (format == "json") {
        const json gains = json::parse(store.artifact(id, "gains.json").value_or("{}"));
        send_json(res, 200, gains.value("history", json::array()));
      } else if (format.empty() || format == "csv") {
        res.set_content(store.artifact(id, "history.csv").value_or(""), "text/csv");
      } else {
        return send_error(res, 400, "invalid_parameter", "format must be csv or json");
      }
    } else {
      if (format == "md")
        res.set_content(store.artifact(id, "comparison.md").value_or(""), "text/markdown");
      else if (format.empty() || format == "json")
        res.set_content(store.artifact(id, "comparison.json").value_or(""), "application/json");
      else
        return send_error(res, 400, "invalid_parameter", "format must be json or md");
    }
  }

  // report.html of a succeeded job: drawn from its stored files on first request, then kept.
  std::string report(const std::string& id) {
    if (auto cached = store.artifact(id, "report.html")) return *cached;
    namespace fs = std::filesystem;
    const fs::path dir =
        fs::temp_directory_path() / ("ftctune-report-" + id + "-" + std::to_string(::getpid()) +
                                     "-" + std::to_string(report_counter++));
    struct Cleanup {
      fs::path dir;
      ~Cleanup() {
        std::error_code ec;
        fs::remove_all(dir, ec);
      }
    } cleanup{dir};
    for (const auto& [name, content] : store.artifacts(id)) write_file_atomic(dir / name, content);
    const ReportResult r = render_report(dir, ReportOptions{});
    const std::string html = read_file(r.html).value_or("");
    store.put_artifact(id, "report.html", html);
    return html;
  }

  void configure_http() {
    const auto handler = [this](const httplib::Request& req, httplib::Response& res) {
      dispatch(req, res);
    };
    // One catch-all route per method: dispatch() tells 404 (no such resource) from 405.
    http.Get(".*", handler);
    http.Post(".*", handler);
    http.Put(".*", handler);
    http.Patch(".*", handler);
    http.Delete(".*", handler);
    http.Options(".*", handler);
    http.set_pre_routing_handler([this](const httplib::Request& req, httplib::Response& res) {
      if (authorised(req)) return httplib::Server::HandlerResponse::Unhandled;
      res.set_header("WWW-Authenticate", "Bearer");
      send_error(res, 401, "unauthorized",
                 "a valid \"Authorization: Bearer <token>\" header is required");
      return httplib::Server::HandlerResponse::Handled;
    });
    // Errors the library produces itself (413 above the body limit, 400 for a malformed
    // request, 404 for an unknown method) get the same JSON body as ours.
    http.set_error_handler([](const httplib::Request&, httplib::Response& res) {
      if (!res.body.empty()) return;
      if (res.status == 413)
        send_error(res, 413, "payload_too_large", "the request body exceeds the server's limit");
      else
        send_error(res, res.status, "http_error", "HTTP status " + std::to_string(res.status));
    });
    http.set_exception_handler(
        [](const httplib::Request&, httplib::Response& res, std::exception_ptr ep) {
          std::string what = "unknown error";
          try {
            std::rethrow_exception(ep);
          } catch (const std::exception& e) {
            what = e.what();
          } catch (...) {
          }
          spdlog::error("request failed: {}", what);
          send_error(res, 500, "internal_error", what);
        });
    http.set_payload_max_length(opt.max_body_bytes);
    http.set_read_timeout(5, 0);
    http.set_write_timeout(5, 0);
    http.set_keep_alive_timeout(5);
  }

  // ---- workers ---------------------------------------------------------------------------------

  void worker_loop() {
    while (!stopping) {
      std::uint64_t seen;
      {
        std::lock_guard<std::mutex> lock(wake_mutex);
        seen = submissions;
      }
      std::optional<JobRecord> job;
      try {
        job = store.claim_next();
      } catch (const std::exception& e) {
        spdlog::error("cannot read the queue: {}", e.what());
      }
      if (!job) {
        // Sleep until a submission newer than our look at the queue (none is missed: `seen`
        // was read before claim_next), or stop.
        std::unique_lock<std::mutex> lock(wake_mutex);
        wake.wait_for(lock, std::chrono::seconds(1),
                      [&] { return stopping.load() || submissions != seen; });
        continue;
      }
      run(*job);
    }
  }

  void run(const JobRecord& rec) {
    const std::string& id = rec.id;
    const auto t0 = std::chrono::steady_clock::now();
    try {
      const Job job = parse_job_text(store.job_json(id), "job " + id);
      std::vector<std::string> names;
      for (const ParameterBounds& b : job.tuning->parameters) names.push_back(b.name);
      const std::optional<std::string> checkpoint = store.checkpoint(id);
      json state;
      RunOptions ro;
      if (checkpoint) {
        state = json::parse(*checkpoint);
        ro.resume = &state;
        spdlog::info("job {} resumes after iteration {} (attempt {})", id, rec.iteration,
                     rec.attempts);
      } else {
        spdlog::info("job {} ({}) started", id, rec.name);
      }
      ro.observer = [&](const HistoryRow& h, const Optimizer& o) {
        json best = json::object();
        for (std::size_t i = 0; i < names.size() && i < h.best.size(); ++i)
          best[names[i]] = h.best[i];
        store.record_progress(id, h.iteration, h.evaluations, h.best_fitness, best,
                              o.state().dump());
        return !stopping && !store.cancel_requested(id);
      };
      TbbEvaluator evaluator(opt.threads);
      const TuningOutcome r = tune(job, evaluator, ro);
      if (store.cancel_requested(id)) {
        store.finish_cancelled(id);
        spdlog::info("job {} cancelled", id);
      } else if (!r.completed()) {
        store.requeue(id);
        spdlog::info("job {} checkpointed and put back in the queue", id);
      } else {
        std::map<std::string, std::string> files = output_files(r);
        const double wall =
            std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        json run = run_metadata(r, wall);
        run["job_id"] = id;
        run["started_at"] = rec.started_at;
        run["attempts"] = rec.attempts;
        files["run.json"] = run.dump(2) + "\n";
        store.finish_succeeded(id, files);
        spdlog::info("job {} succeeded in {:.2f} s: J = {:.6g}", id, wall,
                     r.optimization.best_fitness);
      }
    } catch (const std::exception& e) {
      spdlog::error("job {} failed: {}", id, e.what());
      try {
        store.finish_failed(id, e.what());
      } catch (const std::exception& e2) {
        spdlog::error("job {}: cannot record the failure: {}", id, e2.what());
      }
    }
  }
};

TuningService::TuningService(ServiceOptions options) {
  throw_if_errors("ftctune serve", options.validate());
  impl_ = std::make_unique<Impl>(std::move(options));
}

TuningService::~TuningService() { stop(); }

int TuningService::start() {
  Impl& s = *impl_;
  s.recovered = s.store.recover();
  if (s.recovered > 0)
    spdlog::info("{} job(s) left running by an earlier server are queued again", s.recovered);
  s.configure_http();
  int port = s.opt.port;
  if (port == 0) {
    port = s.http.bind_to_any_port(s.opt.bind);
    if (port <= 0) throw std::runtime_error("cannot bind to " + s.opt.bind);
  } else if (!s.http.bind_to_port(s.opt.bind, port)) {
    throw std::runtime_error("cannot bind to " + s.opt.bind + ":" + std::to_string(port) +
                             " (in use, or not an address of this machine)");
  }
  s.listener = std::thread([&s] { s.http.listen_after_bind(); });
  while (!s.http.is_running()) std::this_thread::sleep_for(std::chrono::milliseconds(1));
  for (int i = 0; i < s.opt.concurrent_jobs; ++i) s.workers.emplace_back([&s] { s.worker_loop(); });
  s.started = true;
  return port;
}

void TuningService::stop() {
  if (!impl_ || !impl_->started) return;
  Impl& s = *impl_;
  s.started = false;
  s.http.stop();
  if (s.listener.joinable()) s.listener.join();
  {
    std::lock_guard<std::mutex> lock(s.wake_mutex);
    s.stopping = true;
  }
  s.wake.notify_all();
  for (std::thread& w : s.workers)
    if (w.joinable()) w.join();
}

int TuningService::recovered_jobs() const { return impl_->recovered; }

}  // namespace ftc::tune
