#pragma once
// The service's workers: each takes the oldest queued job from the store and runs it as `ftctune
// run` does, through the run API (run_job, with the job store as its RunStorage: a checkpoint of
// the optimiser after every iteration, the run's files stored with the job's final status).
// Private to tuner/service.
//
// A store that cannot write (a full disk) costs no finished work and leaves no job stuck: a
// checkpoint it refuses is skipped (the next one carries its trials), a finished job's final
// state and files are kept in memory and written when the store takes them again, retried on a
// timer and before each new job, and a worker holding one claims no new job meanwhile (so at most
// one held result per worker). A cancellation the store cannot record is applied in memory.
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include "ftc/tune/evaluators/batch_evaluator.hpp"
#include "ftc/tune/run/tuning_run.hpp"
#include "ftc/tune/service/job_store.hpp"

namespace ftc::tune::service_detail {

struct RunnerOptions {
  int workers = 1;
  double retry_seconds = 5;  // between attempts to write what the store refused
  std::uint64_t max_stored_bytes = 0;
  std::int64_t trajectory_rows = 0;
};

// A finished job's final state, not yet in the store.
struct Unstored {
  JobStatus status = JobStatus::failed;
  std::string error;        // failed: why
  std::string finished_at;  // when it finished (UTC ISO 8601)
  std::uint64_t bytes = 0;  // of its result files
  int warnings = 0;         // succeeded: those its gains file lists
};

// What the store owes: for /healthz and the answers to submissions.
struct StoreHealth {
  std::optional<std::string> error;  // the last write's failure, until a write succeeds
  std::size_t unstored = 0;          // finished jobs held in memory
  std::size_t cancels = 0;           // cancellations not yet recorded
  bool owes() const { return unstored > 0 || cancels > 0; }
};

class JobRunner {
 public:
  using EvaluatorFactory = std::function<std::unique_ptr<BatchEvaluator>()>;

  JobRunner(JobStore& store, RunnerOptions options, EvaluatorFactory make_evaluator)
      : store_(store), opt_(options), make_evaluator_(std::move(make_evaluator)) {}
  ~JobRunner() { stop(); }

  // Called with a job's id after each change the runner commits (started, an iteration, back
  // in the queue, finished); set before start().
  void on_change(std::function<void(const std::string&)> f) { changed_ = std::move(f); }
  void start();
  // A job was queued: wake a worker.
  void notify();
  // Running jobs checkpoint at the end of their iteration and go back to the queue; returns
  // when every worker has stopped, after a last attempt at writing what the store owes.
  // Idempotent.
  void stop();

  // Every write to the store reports here, so that its health is known to the API too.
  void store_wrote();
  void store_failed(const StoreError& e);
  StoreHealth health();
  // The final state of a finished job the store has not taken yet.
  std::optional<Unstored> unstored(const std::string& id);
  // Cancelling a finished job whose results are held: they are dropped and it ends cancelled.
  // nullopt when none is held for `id`; else the status it had (succeeded: now cancelled).
  std::optional<JobStatus> cancel_unstored(const std::string& id);
  // A cancellation the store could not record: a running job stops after its iteration, a
  // queued one is cancelled when the store writes again (before any job is claimed).
  void defer_cancel(const std::string& id);
  bool cancel_deferred(const std::string& id);
  // A cancel of a job this runner is running: its run stops before its next pack of
  // simulations rather than at the end of its iteration (RunJobOptions::interrupt). Nothing for
  // a job it is not running.
  void interrupt(const std::string& id);

 private:
  struct Held {
    Unstored state;
    std::map<std::string, std::string> files;  // succeeded: its result files
  };
  void worker_loop();
  void run(const JobRecord& rec);
  // Writes a finished job's final state; throws a transient StoreError when the store refused
  // it for now (a job whose files SQLite will never take fails instead). Does not take
  // held_mutex_.
  void write(const std::string& id, Held& h);
  void note_failure(const StoreError& e);  // under held_mutex_
  // Retries what the store owes (or, owing nothing after a refused write, probes it); true when
  // the store writes again.
  bool flush();

  JobStore& store_;
  RunnerOptions opt_;
  EvaluatorFactory make_evaluator_;
  std::function<void(const std::string&)> changed_;
  void changed(const std::string& id) {
    if (changed_) changed_(id);
  }
  std::vector<std::thread> threads_;
  std::atomic<bool> stopping_{false};
  // The running jobs' stop flags (interrupt()), read between packs.
  std::mutex running_mutex_;
  std::map<std::string, std::shared_ptr<std::atomic<bool>>> running_;
  std::mutex wake_mutex_;
  std::condition_variable wake_;
  std::uint64_t submissions_ = 0;  // bumped under wake_mutex_ on every submission

  // Guards the members below; flush() holds it while it writes, so that a held job cannot be
  // cancelled half-way through being stored.
  std::mutex held_mutex_;
  std::map<std::string, Held> held_;
  std::set<std::string> cancels_;
  std::optional<std::string> store_error_;
};

}  // namespace ftc::tune::service_detail
