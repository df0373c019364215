#pragma once
// The HTTP API of the service (docs/service.md): routes, authentication, JSON errors, the
// submission budget and queue quota. It reads and writes the job store, tells the runner about
// new jobs, and shows what the runner holds while the store cannot write (then it answers 507).
// Private to tuner/service.
#include <atomic>
#include <nlohmann/json.hpp>
#include <string>

#include "ftc/tune/service/job_store.hpp"
#include "ftc/tune/service/service.hpp"
#include "service/httplib.hpp"
#include "service/job_runner.hpp"

namespace ftc::tune::service_detail {

class Api {
 public:
  Api(const ServiceOptions& options, JobStore& store, JobRunner& runner)
      : opt_(options), store_(store), runner_(runner) {}

  // Installs the routes and handlers on a server.
  void configure(httplib::Server& http);

 private:
  bool authorised(const httplib::Request& req) const;
  void method_not_allowed(httplib::Response& res, const char* allow);
  void dispatch(const httplib::Request& req, httplib::Response& res);
  void submit(const httplib::Request& req, httplib::Response& res);
  void list(const httplib::Request& req, httplib::Response& res);
  void cancel(const std::string& id, httplib::Response& res);
  void result(const httplib::Request& req, httplib::Response& res, const std::string& id,
              const std::string& what);
  std::string report(const std::string& id);
  nlohmann::json view(const JobRecord& r);
  // 507: the store cannot write (`why`), with what it owes.
  void insufficient_storage(httplib::Response& res, const std::string& why);

  const ServiceOptions& opt_;
  JobStore& store_;
  JobRunner& runner_;
  std::atomic<int> report_counter_{0};
};

}  // namespace ftc::tune::service_detail
