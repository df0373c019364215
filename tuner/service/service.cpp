#include "ftc/tune/service/service.hpp"

#include <spdlog/spdlog.h>

#include <chrono>
#include <thread>

#include "ftc/tune/evaluators/tbb_evaluator.hpp"
#include "ftc/tune/service/job_store.hpp"
#include "service/api.hpp"
#include "service/httplib.hpp"
#include "service/job_runner.hpp"

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

struct TuningService::Impl {
  ServiceOptions opt;
  JobStore store;
  service_detail::JobRunner runner;
  service_detail::Api api;
  httplib::Server http;
  std::thread listener;
  int recovered = 0;
  bool started = false;

  explicit Impl(ServiceOptions o)
      : opt(std::move(o)),
        store(opt.store),
        runner(store, opt.concurrent_jobs,
               opt.evaluator ? opt.evaluator
                             : service_detail::JobRunner::EvaluatorFactory([t = opt.threads] {
                                 return std::make_unique<TbbEvaluator>(t);
                               })),
        api(opt, store, [this] { runner.notify(); }) {}
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
  s.api.configure(s.http);
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
  s.runner.start();
  s.started = true;
  return port;
}

void TuningService::stop() {
  if (!impl_ || !impl_->started) return;
  Impl& s = *impl_;
  s.started = false;
  s.http.stop();
  if (s.listener.joinable()) s.listener.join();
  s.runner.stop();
}

int TuningService::recovered_jobs() const { return impl_->recovered; }

}  // namespace ftc::tune
