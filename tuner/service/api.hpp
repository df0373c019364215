#pragma once
// The HTTP API of the service (docs/service.md): routes, authentication, JSON errors, the
// submission budget. It reads and writes the job store and tells the runner about new jobs.
// Private to tuner/service.
#include <atomic>
#include <functional>
#include <string>

#include "ftc/tune/service/job_store.hpp"
#include "ftc/tune/service/service.hpp"
#include "service/httplib.hpp"

namespace ftc::tune::service_detail {

class Api {
 public:
  Api(const ServiceOptions& options, JobStore& store, std::function<void()> on_submit)
      : opt_(options), store_(store), on_submit_(std::move(on_submit)) {}

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

  const ServiceOptions& opt_;
  JobStore& store_;
  std::function<void()> on_submit_;
  std::atomic<int> report_counter_{0};
};

}  // namespace ftc::tune::service_detail
