#pragma once
// The HTTP API of the service (docs/service.md): routes, authentication, JSON errors, the
// submission budget and queue quota. It reads and writes the job store, tells the runner about
// new jobs, and shows what the runner holds while the store cannot write (then it answers 507).
// Private to tuner/service.
#include <algorithm>
#include <atomic>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <nlohmann/json.hpp>
#include <string>

#include "ftc/tune/job/job.hpp"
#include "ftc/tune/run/tuning_run.hpp"
#include "ftc/tune/service/job_store.hpp"
#include "ftc/tune/service/service.hpp"
#include "service/checker.hpp"
#include "service/events.hpp"
#include "service/httplib.hpp"
#include "service/job_runner.hpp"

namespace ftc::tune::service_detail {

class Api {
 public:
  Api(const ServiceOptions& options, JobStore& store, JobRunner& runner)
      : opt_(options),
        store_(store),
        runner_(runner),
        hub_(static_cast<std::size_t>(
                 std::clamp(options.max_event_streams, 0, options.max_connections / 2)),
             static_cast<std::size_t>(std::max(options.max_event_streams_per_client, 0))) {}

  // Job `id` changed in the store (or left it): its view goes to every open event stream.
  // Never throws.
  void changed(const std::string& id) noexcept;
  // The server stops: every event stream ends.
  void close_events() { hub_.close(); }

  // Installs the routes and handlers on a server.
  void configure(httplib::Server& http);

  // What the handlers configure() installs do with one request the library has parsed: the
  // token check, then, for a method with a body (`body` not null), reading it under the size
  // limit, then the resource. Exceptions escape (the server's exception handler answers them:
  // 500, or 507 for a store that cannot write). This is the API without a socket, for the fuzz
  // target.
  void handle(const httplib::Request& req, httplib::Response& res,
              const httplib::ContentReader* body);

 private:
  bool authorised(const httplib::Request& req) const;
  // Without a token: the Host must be a loopback name or the bound address (a page of another
  // site that reached the service through DNS rebinding names its own), and a request that
  // changes something (not GET, HEAD or OPTIONS) must not come from a page of another origin.
  // False after answering 403.
  bool same_origin(const httplib::Request& req, httplib::Response& res) const;
  // False after answering 403 (same_origin) or 401.
  bool authenticate(const httplib::Request& req, httplib::Response& res) const;
  // Reads the body under the limit (413 above it), then dispatches.
  void receive(const httplib::Request& req, httplib::Response& res,
               const httplib::ContentReader& read);
  void method_not_allowed(httplib::Response& res, const char* allow);
  void dispatch(const httplib::Request& req, httplib::Response& res);
  // The checks a submission passes (JSON, job, size budgets) on the body; nullopt after
  // answering 400 or 413.
  std::optional<Job> check_job(const std::string& body, httplib::Response& res) const;
  // check_job on the checker's worker, under the check deadline: nullopt after answering it
  // (or 503 when the deadline passed), or when the client hung up.
  std::optional<Job> checked_job(const httplib::Request& req, httplib::Response& res);
  void validate(const httplib::Request& req, httplib::Response& res);
  void submit(const httplib::Request& req, httplib::Response& res);
  void running_result(const httplib::Request& req, httplib::Response& res, const JobRecord& job,
                      const std::string& what);
  TuningOutcome outcome_of(const std::string& id, const JobStore::Checkpoint& c);
  void files(const std::string& id, const std::string& name, httplib::Response& res);
  void events(const httplib::Request& req, const std::string& job, httplib::Response& res);
  void list(const httplib::Request& req, httplib::Response& res);
  void cancel(const std::string& id, httplib::Response& res);
  void result(const httplib::Request& req, httplib::Response& res, const std::string& id,
              const std::string& what);
  std::string report(const std::string& id);
  // Stores a file made from a job's stored ones (report.html, held-out.json), which is served
  // all the same when the store cannot take it.
  void keep(const std::string& id, const std::string& name, const std::string& content);
  // GET /v1/jobs/{id}/held-out?count=N[&seed=S]: the job's front on held-out members.
  void held_out(const httplib::Request& req, httplib::Response& res, const std::string& id);
  nlohmann::json view(const JobRecord& r);
  // 507: the store cannot write (`why`), with what it owes.
  void insufficient_storage(httplib::Response& res, const std::string& why);

  const ServiceOptions& opt_;
  JobStore& store_;
  JobRunner& runner_;
  EventHub hub_;
  // A running job's partial results, made from its checkpoint of `iteration`: trials.csv,
  // history.csv, the history as JSON, and gains.json once asked for (a comparison).
  struct PartialResults {
    int iteration = -1;
    std::string trials, history, history_rows;
    std::optional<std::string> gains;
  };
  std::mutex partial_mutex_;  // guards partial_ and making_
  // Per job, held by the one request making its partial results (one job's comparison does not
  // hold up another's trials): shared by the requests that use it, dropped when none does.
  std::map<std::string, std::weak_ptr<std::mutex>> making_;
  std::shared_ptr<std::mutex> making_mutex(const std::string& id);
  std::map<std::string, std::shared_ptr<const PartialResults>> partial_;  // by running job
  // Last, so that it stops (and its worker, which reads opt_, ends) before anything else goes.
  Checker checker_;
};

}  // namespace ftc::tune::service_detail
