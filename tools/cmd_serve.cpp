// ftctune serve: the tuning service. SIGTERM or SIGINT shut it down gracefully.
#include <spdlog/spdlog.h>
#include <netdb.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <csignal>
#include <cstdio>
#include <fstream>
#include <sstream>

#include "cli.hpp"
#include "ftc/sim/input_error.hpp"
#include "ftc/tune/io/files.hpp"
#include "ftc/tune/service/service.hpp"

namespace ftc::cli {
namespace {

struct ServeOptions {
  tune::ServiceOptions service;
  std::string token_file;
  std::size_t max_body_kib = 1024;
  std::uint64_t max_stored_mib = 256;
  std::uint64_t max_job_mib = 1024;
  bool event_streams_given = false;  // --max-event-streams on the command line
};

std::string read_token(const std::string& file) {
  // A token others can read is no secret: refuse it as ssh refuses a private key.
  struct stat st {};
  if (::stat(file.c_str(), &st) == 0 && (st.st_mode & (S_IRWXG | S_IRWXO)) != 0) {
    char mode[8];
    std::snprintf(mode, sizeof mode, "%04o", static_cast<unsigned>(st.st_mode & 07777));
    throw InputError("--token-file", "",
                     file + " is accessible by other users (mode " + mode + "); chmod 600 " + file);
  }
  const std::optional<std::string> text = tune::read_file(file);
  if (!text) throw InputError("--token-file", "", "cannot read " + file);
  std::string t = *text;
  while (!t.empty() && std::isspace(static_cast<unsigned char>(t.back()))) t.pop_back();
  while (!t.empty() && std::isspace(static_cast<unsigned char>(t.front()))) t.erase(0, 1);
  return t;
}

// Refuses a port another process listens on before the service opens (and creates) its store:
// the service's own bind says the same, but only after the store exists. A port 0 (any free
// one) and names that do not resolve are left to it.
void refuse_port_in_use(const std::string& bind, int port) {
  if (port == 0) return;
  addrinfo hints{};
  hints.ai_socktype = SOCK_STREAM;
  hints.ai_flags = AI_PASSIVE | AI_NUMERICSERV;
  addrinfo* found = nullptr;
  if (::getaddrinfo(bind.c_str(), std::to_string(port).c_str(), &hints, &found) != 0) return;
  bool in_use = false;
  for (addrinfo* a = found; a && !in_use; a = a->ai_next) {
    const int fd = ::socket(a->ai_family, a->ai_socktype | SOCK_CLOEXEC, a->ai_protocol);
    if (fd < 0) continue;
    int yes = 1;  // as the service binds: a port in TIME_WAIT is free
    ::setsockopt(fd, SOL_SOCKET, SO_REUSEADDR, &yes, sizeof yes);
    in_use = ::bind(fd, a->ai_addr, a->ai_addrlen) != 0 && errno == EADDRINUSE;
    ::close(fd);
  }
  ::freeaddrinfo(found);
  if (in_use)
    throw InputError("--port", "",
                     "cannot listen on " + bind + ":" + std::to_string(port) +
                         ": address in use (is another server listening on that port?)");
}

int run_serve(ServeOptions o) {
  if (!o.token_file.empty()) o.service.token = read_token(o.token_file);
  // The service keeps half its connection threads for the API: a larger number asked for is
  // refused rather than quietly cut (the default follows --max-connections).
  if (o.event_streams_given && o.service.max_event_streams > o.service.max_connections / 2)
    throw InputError("--max-event-streams", "",
                     "must be at most half of --max-connections (" +
                         std::to_string(o.service.max_connections / 2) +
                         " with --max-connections " +
                         std::to_string(o.service.max_connections) +
                         "): each stream holds a connection thread");
  o.service.max_body_bytes = o.max_body_kib * 1024;
  o.service.max_stored_bytes = o.max_stored_mib << 20;
  o.service.max_job_memory_bytes = o.max_job_mib << 20;

  // Block the shutdown signals in every thread (the workers inherit the mask); this thread
  // waits for them with sigwait.
  sigset_t signals;
  sigemptyset(&signals);
  sigaddset(&signals, SIGTERM);
  sigaddset(&signals, SIGINT);
  pthread_sigmask(SIG_BLOCK, &signals, nullptr);

  // Under mpirun each job runs on every rank, one job at a time (MPI calls are serialized).
  if (mpi_ranks() > 1) {
    if (o.service.concurrent_jobs != 1)
      throw InputError(
          "--concurrent-jobs", "",
          "must be 1 under mpirun: each job runs on all " + std::to_string(mpi_ranks()) + " ranks");
    // Greets the ranks once now, so a rank that does not answer stops the start, not a job.
    const int threads = o.service.threads;
    spdlog::info("serving with {} MPI ranks ({} threads)", mpi_ranks(),
                 make_evaluator(threads)->concurrency());
    o.service.evaluator = [threads] { return make_evaluator(threads); };
  }
  refuse_port_in_use(o.service.bind, o.service.port);
  tune::TuningService service(o.service);
  const int port = service.start();  // a bind failure is an InputError: exit 2
  // An IPv6 address in a URL goes in brackets (RFC 3986): http://[::1]:8080.
  const std::string host = o.service.bind.find(':') != std::string::npos &&
                                   o.service.bind.front() != '['
                               ? "[" + o.service.bind + "]"
                               : o.service.bind;
  std::printf("ftctune serve: listening on http://%s:%d (store %s, %d concurrent job%s%s)\n",
              host.c_str(), port, o.service.store.c_str(), o.service.concurrent_jobs,
              o.service.concurrent_jobs == 1 ? "" : "s", o.service.token ? ", token required" : "");
  std::fflush(stdout);

  int sig = 0;
  sigwait(&signals, &sig);
  spdlog::info("{}: stopping; running jobs are checkpointed and stay queued",
               sig == SIGTERM ? "SIGTERM" : "SIGINT");
  service.stop();
  spdlog::info("stopped");
  return 0;
}

}  // namespace

void add_serve_command(CLI::App& app, Globals& g, Action& action) {
  auto o = std::make_shared<ServeOptions>();
  CLI::App* sub =
      app.add_subcommand("serve", "Run the tuning service (HTTP API, durable job store)");
  sub->add_option("--bind", o->service.bind, "Address to listen on (default 127.0.0.1)");
  sub->add_option("--port", o->service.port, "Port (default 8080; 0 = any free port)");
  sub->add_option("--store", o->service.store, "Store directory (default ./ftctune-store)");
  sub->add_option("--concurrent-jobs", o->service.concurrent_jobs, "Jobs run at once (default 1)");
  sub->add_option("--threads", o->service.threads, "Threads per job (default: all cores)")
      ->check(CLI::Range(0, 4096));
  sub->add_option("--plugin", g.plugins,
                  "A plant plugin (ftctune_plant_NAME.so) jobs may name as plugin:NAME; "
                  "repeatable. The server loads no other library, whatever a job names")
      ->check(CLI::ExistingFile);
  sub->add_option("--token-file", o->token_file,
                  "File holding the bearer token every request must carry");
  sub->add_option("--max-body-kib", o->max_body_kib,
                  "Largest accepted request body in KiB (default 1024)");
  sub->add_option(
      "--max-steps", o->service.max_steps,
      "Largest accepted job: evaluations x simulated steps per evaluation (default 2e9)");
  sub->add_option("--max-attempts", o->service.max_attempts,
                  "Starts of a job before crash recovery gives it up as failed (default 5)")
      ->check(CLI::Range(1, 1000));
  sub->add_option("--max-stored-mib", o->max_stored_mib,
                  "Largest result of one job in MiB, trials checkpoints included (default 256)")
      ->check(CLI::Range(1, 900));
  sub->add_option("--max-job-mib", o->max_job_mib,
                  "Most memory one job may need, by its estimate, in MiB; larger jobs get 413 "
                  "(default 1024)")
      ->check(CLI::Range(64, 1 << 20));
  sub->add_option("--trajectory-rows", o->service.trajectory_rows,
                  "Rows per stored comparison trajectory: longer scenarios are recorded more "
                  "coarsely than every 10 ms (default 20000)")
      ->check(CLI::Range(std::int64_t{100}, std::int64_t{100000000}));
  sub->add_option("--max-queued", o->service.max_queued,
                  "Jobs the queue holds; more get 503 (default 500; 0 = no limit)")
      ->check(CLI::Range(std::int64_t{0}, std::int64_t{1000000000}));
  sub->add_option("--max-queued-per-client", o->service.max_queued_per_client,
                  "Queued jobs per client address; more get 429 (default 100; 0 = no limit)")
      ->check(CLI::Range(std::int64_t{0}, std::int64_t{1000000000}));
  sub->add_option("--header-timeout", o->service.header_timeout,
                  "Seconds a request's headers may take from its first byte (default 10)")
      ->check(CLI::Range(0.1, 3600.0));
  sub->add_option("--body-timeout", o->service.body_timeout,
                  "Seconds a request's body may take after its headers (default 60)")
      ->check(CLI::Range(0.1, 3600.0));
  sub->add_option("--check-timeout", o->service.check_timeout,
                  "Seconds a submitted or validated job may wait for and take its check; the "
                  "server checks one at a time (default 10)")
      ->check(CLI::Range(0.01, 3600.0));
  sub->add_option("--max-connections", o->service.max_connections,
                  "Connections served at once (default 64)")
      ->check(CLI::Range(2, 1024));
  sub->add_option("--max-connections-per-client", o->service.max_connections_per_client,
                  "Connections one address may hold at once; more get 429 (default 16)")
      ->check(CLI::Range(1, 1023));
  sub->add_option("--max-event-streams", o->service.max_event_streams,
                  "Live-update streams (the dashboard's pages) open at once, each holding a "
                  "connection; more get 503 (default 32, at most half of --max-connections)")
      ->check(CLI::Range(0, 1023));
  sub->add_option("--max-event-streams-per-client", o->service.max_event_streams_per_client,
                  "Live-update streams one address may hold at once; more get 429 (default 8, "
                  "0: no limit)")
      ->check(CLI::Range(0, 1023));
  sub->callback([&action, o, sub, &g] {
    o->event_streams_given = sub->count("--max-event-streams") > 0;
    o->service.plugins.assign(g.plugins.begin(), g.plugins.end());
    action = [o] { return run_serve(*o); };
  });
}

}  // namespace ftc::cli
