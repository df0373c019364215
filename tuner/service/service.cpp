#include "ftc/tune/service/service.hpp"

#include <arpa/inet.h>
#include <netdb.h>
#include <netinet/in.h>
#include <spdlog/spdlog.h>
#include <sys/socket.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstring>
#include <thread>

#include "ftc/sim/plant_plugin.hpp"
#include "ftc/tune/evaluators/tbb_evaluator.hpp"
#include "ftc/tune/service/job_store.hpp"
#include "service/api.hpp"
#include "service/http_server.hpp"
#include "service/httplib.hpp"
#include "service/job_runner.hpp"

namespace ftc::tune {

using nlohmann::json;

namespace {

// Why `host` is not loopback only ("" when it is): the addresses it resolves to are compared,
// not its spelling, since a name like 127.x.example may resolve anywhere, and the server listens
// on whichever of its addresses binds.
std::string not_loopback(const std::string& host) {
  addrinfo hints{};
  hints.ai_family = AF_UNSPEC;
  hints.ai_socktype = SOCK_STREAM;
  hints.ai_flags = AI_PASSIVE;
  addrinfo* found = nullptr;
  if (const int rc = ::getaddrinfo(host.c_str(), nullptr, &hints, &found); rc != 0)
    return std::string("cannot resolve it: ").append(::gai_strerror(rc));
  if (found == nullptr) return "it resolves to no address";
  std::string outside;
  for (const addrinfo* a = found; a != nullptr; a = a->ai_next) {
    bool loopback = false;
    char text[INET6_ADDRSTRLEN] = "?";
    if (a->ai_family == AF_INET) {
      const in_addr& v4 = reinterpret_cast<const sockaddr_in*>(a->ai_addr)->sin_addr;
      loopback = (ntohl(v4.s_addr) >> 24) == 127;
      ::inet_ntop(AF_INET, &v4, text, sizeof text);
    } else if (a->ai_family == AF_INET6) {
      const in6_addr& v6 = reinterpret_cast<const sockaddr_in6*>(a->ai_addr)->sin6_addr;
      loopback = IN6_IS_ADDR_LOOPBACK(&v6) || (IN6_IS_ADDR_V4MAPPED(&v6) && v6.s6_addr[12] == 127);
      ::inet_ntop(AF_INET6, &v6, text, sizeof text);
    }
    if (!loopback && outside.empty()) outside = text;
  }
  ::freeaddrinfo(found);
  return outside.empty() ? "" : std::string("it resolves to ").append(outside);
}

// Why a bind failed, from its errno.
std::string bind_failure(int err) {
  switch (err) {
    case EADDRINUSE:
      return "address in use (is another server listening on that port?)";
    case EADDRNOTAVAIL:
      return "not an address of this machine";
    case EACCES:
      return "permission denied (ports below 1024 need privileges)";
    default:
      return err != 0 ? std::strerror(err) : "the address cannot be bound";
  }
}

}  // namespace

bool is_loopback(const std::string& host) { return not_loopback(host).empty(); }

std::vector<FieldError> ServiceOptions::validate() const {
  std::vector<FieldError> errs;
  if (!token)
    if (const std::string why = not_loopback(bind); !why.empty())
      errs.push_back({"--bind", std::string("refusing to listen on ")
                                    .append(bind)
                                    .append(" without --token-file: it is not loopback (")
                                    .append(why)
                                    .append("), so anyone who can reach it could submit jobs")});
  if (port < 0 || port > 65535) errs.push_back({"--port", "must be in 0..65535"});
  if (concurrent_jobs < 1 || concurrent_jobs > 64)
    errs.push_back({"--concurrent-jobs", "must be in 1..64"});
  if (token && token->empty()) errs.push_back({"--token-file", "the token is empty"});
  // A client sends it as "Authorization: Bearer TOKEN": a token with a space, a line break or
  // a control character could never match, and every request would be 401.
  if (token && std::any_of(token->begin(), token->end(), [](char c) {
        return static_cast<unsigned char>(c) <= ' ' || c == '\x7f';
      }))
    errs.push_back({"--token-file",
                    "the token holds a space, a line break or a control character inside it; "
                    "give one line of printable characters"});
  if (max_body_bytes < 1024) errs.push_back({"--max-body-kib", "must be at least 1 KiB"});
  if (max_attempts < 1) errs.push_back({"--max-attempts", "must be at least 1"});
  if (!(max_steps > 0)) errs.push_back({"--max-steps", "must be > 0"});
  if (max_job_memory_bytes < (std::uint64_t{64} << 20))
    errs.push_back({"--max-job-mib", "must be at least 64"});
  // SQLite stores no value above 1e9 bytes; every result file of a job is below its limit.
  if (max_stored_bytes < (std::uint64_t{1} << 20) || max_stored_bytes > (std::uint64_t{900} << 20))
    errs.push_back({"--max-stored-mib", "must be in 1..900"});
  if (trajectory_rows < 100) errs.push_back({"--trajectory-rows", "must be at least 100"});
  if (max_queued < 0) errs.push_back({"--max-queued", "must be >= 0 (0: no limit)"});
  if (max_queued_per_client < 0)
    errs.push_back({"--max-queued-per-client", "must be >= 0 (0: no limit)"});
  if (!(header_timeout >= 0.1 && header_timeout <= 3600))
    errs.push_back({"--header-timeout", "must be in 0.1..3600 seconds"});
  if (!(body_timeout >= 0.1 && body_timeout <= 3600))
    errs.push_back({"--body-timeout", "must be in 0.1..3600 seconds"});
  if (max_connections < 2 || max_connections > 1024)
    errs.push_back({"--max-connections", "must be in 2..1024"});
  if (max_connections_per_client < 1 || max_connections_per_client >= max_connections)
    errs.push_back({"--max-connections-per-client",
                    "must be at least 1 and below --max-connections (so that one client cannot "
                    "take every connection)"});
  if (max_event_streams < 0) errs.push_back({"--max-event-streams", "must be >= 0"});
  if (max_event_streams_per_client < 0)
    errs.push_back({"--max-event-streams-per-client", "must be >= 0 (0: no limit)"});
  if (!(check_timeout >= 0.01 && check_timeout <= 3600))
    errs.push_back({"--check-timeout", "must be in 0.01..3600 seconds"});
  if (!(store_retry_seconds > 0)) errs.push_back({"store_retry_seconds", "must be > 0"});
  return errs;
}

namespace {

service_detail::ConnectionLimits connection_limits(const ServiceOptions& o) {
  const auto ms = [](double seconds) {
    return std::chrono::milliseconds(std::llround(seconds * 1000));
  };
  service_detail::ConnectionLimits l;
  l.header_timeout = ms(o.header_timeout);
  l.body_timeout = ms(o.body_timeout);
  l.per_client = o.max_connections_per_client;
  l.threads = o.max_connections;
  return l;
}

}  // namespace

struct TuningService::Impl {
  ServiceOptions opt;
  JobStore store;
  service_detail::JobRunner runner;
  service_detail::Api api;
  service_detail::GuardedServer http;
  std::thread listener;
  int recovered = 0;
  bool started = false;

  explicit Impl(ServiceOptions o)
      : opt(std::move(o)),
        store(opt.store),
        runner(store,
               {opt.concurrent_jobs, opt.store_retry_seconds, opt.max_stored_bytes,
                opt.trajectory_rows},
               opt.evaluator ? opt.evaluator
                             : service_detail::JobRunner::EvaluatorFactory([t = opt.threads] {
                                 return std::make_unique<TbbEvaluator>(t);
                               })),
        api(opt, store, runner),
        http(connection_limits(opt)) {
    runner.on_change([this](const std::string& id) { api.changed(id); });
  }
};

TuningService::TuningService(ServiceOptions options) {
  throw_if_errors("ftctune serve", options.validate());
  // Its plugins now, and no other library later (ftc/sim/plant_plugin.hpp).
  for (const std::filesystem::path& lib : options.plugins) {
    const sim::PlantPlugin& p = sim::load_plant_plugin(lib);
    spdlog::info("plant plugin plugin:{} from {}", p.name, p.file.string());
  }
  sim::lock_plant_plugins();
  impl_ = std::make_unique<Impl>(std::move(options));
}

TuningService::~TuningService() { stop(); }

int TuningService::start() {
  Impl& s = *impl_;
  const JobStore::Recovery rec = s.store.recover(s.opt.max_attempts);
  s.recovered = rec.requeued;
  if (rec.requeued > 0)
    spdlog::info("{} job(s) left running by an earlier server are queued again", rec.requeued);
  if (rec.failed > 0)
    spdlog::warn("{} job(s) left running by an earlier server have been started {} times: failed",
                 rec.failed, s.opt.max_attempts);
  s.api.configure(s.http);
  // cpp-httplib's default sets SO_REUSEPORT, with which a second server on the same port binds
  // too and the kernel splits the connections between the two. SO_REUSEADDR alone still allows
  // a restart while old connections linger in TIME_WAIT.
  s.http.set_socket_options([](socket_t sock) {
    int yes = 1;
    ::setsockopt(sock, SOL_SOCKET, SO_REUSEADDR, &yes, sizeof yes);
  });
  int port = s.opt.port;
  errno = 0;
  const bool bound = port == 0 ? (port = s.http.bind_to_any_port(s.opt.bind)) > 0
                               : s.http.bind_to_port(s.opt.bind, port);
  if (!bound) {
    const int err = errno;
    throw InputError(s.opt.port == 0 ? "--bind" : "--port", "",
                     std::string("cannot listen on ")
                         .append(s.opt.bind)
                         .append(":")
                         .append(std::to_string(s.opt.port))
                         .append(": ")
                         .append(bind_failure(err)));
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
  s.api.close_events();  // the streams end, so the server's threads can be joined
  s.http.stop();
  if (s.listener.joinable()) s.listener.join();
  s.runner.stop();
}

int TuningService::recovered_jobs() const { return impl_->recovered; }

}  // namespace ftc::tune
