#pragma once
// The tuning service behind `ftctune serve`: an HTTP/JSON API (cpp-httplib) in front of a
// durable SQLite job store, and worker threads that run queued jobs in submission order with the
// same tuner as `ftctune run`. See docs/service.md for the API.
//
// Durability: a job's progress and optimiser checkpoint are committed after every iteration, so
// after a crash start() puts running jobs back in the queue and they resume from their last
// iteration, ending with the same gains file an uninterrupted run gives. stop() (SIGTERM)
// stops accepting requests, lets each running job finish its current iteration, checkpoints
// it back into the queue, and returns.
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "ftc/sim/input_error.hpp"
#include "ftc/tune/evaluators/batch_evaluator.hpp"

namespace ftc::tune {

struct ServiceOptions {
  std::string bind = "127.0.0.1";
  int port = 8080;  // 0: any free port (start() returns it)
  std::filesystem::path store = "ftctune-store";
  int concurrent_jobs = 1;
  int threads = 0;  // TBB threads per job; <= 0: all cores
  std::optional<std::string>
      token;  // when set, every request needs "Authorization: Bearer <token>"
  std::size_t max_body_bytes = 1 << 20;
  double max_steps = 2e9;  // budget: evaluations × simulated steps per evaluation
  int max_attempts = 5;    // starts of a job before a crash recovery gives it up
  // What one job may store: its result files, and its checkpointed trials while it runs.
  std::uint64_t max_stored_bytes = std::uint64_t{256} << 20;
  // What one job may hold in memory while it runs (run/memory_budget.hpp's estimate): a job
  // above it is refused when submitted (413).
  std::uint64_t max_job_memory_bytes = std::uint64_t{1} << 30;
  // Rows per stored comparison trajectory: a scenario longer than this many 10 ms rows is
  // recorded at a coarser interval.
  std::int64_t trajectory_rows = 20000;
  // Jobs waiting in the queue, in all and per client address (0: no limit).
  std::int64_t max_queued = 500;
  std::int64_t max_queued_per_client = 100;
  // Slow clients: a request's header block must arrive within header_timeout of its first byte
  // and its body within body_timeout of the headers' end; connections are served by
  // max_connections threads, at most max_connections_per_client of them from one address.
  double header_timeout = 10;
  double body_timeout = 60;
  int max_connections = 64;
  int max_connections_per_client = 16;
  // Live-update streams (GET /v1/events) open at once: each holds one of the max_connections
  // threads for as long as its page is open, so at most half of them are streams whatever this
  // says (the API keeps the other half; `serve` refuses a --max-event-streams above that).
  int max_event_streams = 32;
  // ... and at most this many from one client address (0: no such limit); more are answered 429.
  int max_event_streams_per_client = 8;
  // A submitted or validated job is parsed and checked on one worker thread, one job at a time;
  // a request whose job has not been checked within this many seconds (waiting its turn
  // included) is answered 503.
  double check_timeout = 10;
  // How often results the store could not take (a full disk) are tried again.
  double store_retry_seconds = 5;
  // The plant plugins (ftctune_plant_NAME.so) its jobs may name as "plugin:NAME": loaded when the
  // service is made, after which this process loads no other library (a job naming another
  // plugin is refused at /plant/model, 422). Nothing a job says can make the server load code.
  std::vector<std::filesystem::path> plugins;
  // How each job's simulations run; default a TbbEvaluator with `threads` workers.
  std::function<std::unique_ptr<BatchEvaluator>()> evaluator;

  // Every bad option, e.g. a non-loopback bind without a token.
  std::vector<FieldError> validate() const;
};

// True when every address `host` resolves to is a loopback one (127.0.0.0/8, ::1); false when
// it cannot be resolved.
bool is_loopback(const std::string& host);

class TuningService {
 public:
  // Opens (or creates) the store; throws std::runtime_error when it is locked by another server.
  explicit TuningService(ServiceOptions options);
  ~TuningService();
  TuningService(const TuningService&) = delete;
  TuningService& operator=(const TuningService&) = delete;

  // Recovers crashed jobs, binds, starts the listener and the workers; returns the bound port.
  // Throws InputError when the address cannot be bound (in use by another server, not an
  // address of this machine).
  int start();
  // Graceful shutdown, see above. Idempotent.
  void stop();

  int recovered_jobs() const;  // jobs put back in the queue by start()

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace ftc::tune
