#pragma once
// The tuning service's durable store: one SQLite database (WAL mode) in the store directory.
// Jobs, their progress, optimiser checkpoints and result files live in it, and every state change
// is one committed transaction, so a killed server loses nothing that was acknowledged.
// Submissions, results and cancellations are synced to disk (synchronous=FULL); per-iteration
// progress is not, which costs at most a resumed iteration after a power cut. Thread-safe (one
// connection behind a mutex). SQLite's errors are StoreErrors; a failed write changes nothing.
#include <cstdint>
#include <filesystem>
#include <map>
#include <memory>
#include <mutex>
#include <nlohmann/json.hpp>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

struct sqlite3;

namespace ftc::tune {

enum class JobStatus { queued, running, succeeded, failed, cancelled };
const char* to_string(JobStatus s);
std::optional<JobStatus> job_status_from_string(std::string_view s);
inline bool is_terminal(JobStatus s) {
  return s == JobStatus::succeeded || s == JobStatus::failed || s == JobStatus::cancelled;
}

struct JobRecord {
  std::string id;
  std::int64_t seq = 0;  // submission order
  std::string name;
  JobStatus status = JobStatus::queued;
  std::string created_at, started_at, finished_at, updated_at;  // UTC ISO 8601, "" = not yet
  int iteration = -1;  // last completed optimiser iteration, -1 = none
  int iterations = 0;
  std::int64_t evaluations = 0;
  std::int64_t total_evaluations = 0;
  std::optional<double> best_fitness;
  nlohmann::json best = nlohmann::json::object();  // parameter name → value
  std::string error;
  bool cancel_requested = false;
  int attempts = 0;  // how many times a worker started it
  // What its J measures (documents.hpp's fitness_label: the metric, window and aggregate, not
  // the plant), by which a list groups J values; "" in a store older than this field.
  std::string objective;
  // Of a succeeded run: the warnings its gains file lists; -1 for a job that finished under a
  // server older than this field (not counted).
  int warnings = 0;
};

struct Submission {
  std::string job_json;  // canonical JSON of the validated job
  std::string name;
  int iterations = 0;
  std::int64_t total_evaluations = 0;
  std::optional<std::string> idempotency_key;
  std::string client;  // who submitted it (the peer address), for the per-client queue quota
  std::string objective;  // JobRecord::objective
};

// How many jobs may wait in the queue, in all and per client; 0: no limit.
struct QueueQuota {
  std::int64_t total = 0;
  std::int64_t per_client = 0;
};

struct Submitted {
  enum class Refusal { none, queue_full, client_quota };
  Refusal refused = Refusal::none;
  std::int64_t queued = 0;  // when refused: the jobs queued (in all, or the client's)
  JobRecord record;         // the job (the existing one for a reused idempotency key)
  bool created = false;
};

// What SQLite refused, with its primary result code. transient(): a full disk, an I/O error, a
// busy or read-only database, no memory: the same write may succeed later, unchanged.
class StoreError : public std::runtime_error {
 public:
  StoreError(const std::string& what, int code) : std::runtime_error(what), code_(code) {}
  int code() const { return code_; }
  bool full() const;  // SQLITE_FULL: the disk (or the quota) is full
  bool transient() const;

 private:
  int code_;
};

// A test seam for a full disk that needs no root: from the `after`-th write to any store's files
// (counting from this call, from 1), every write fails with SQLITE_FULL, as it does once a disk
// has filled up, until inject_store_full(0) frees the "disk".
void inject_store_full(int after);

class JobStore {
 public:
  explicit JobStore(const std::filesystem::path& directory);
  ~JobStore();
  JobStore(const JobStore&) = delete;
  JobStore& operator=(const JobStore&) = delete;

  const std::filesystem::path& database() const { return db_path_; }

  // A new queued job; with an idempotency key already used, the existing job (not created).
  // Refused, and nothing written, when the queue or the client's share of it is full.
  Submitted submit(const Submission& s, const QueueQuota& quota = {});
  std::optional<JobRecord> get(const std::string& id);
  std::string job_json(const std::string& id);
  // Newest first; with `name`, only the jobs whose name contains it.
  std::vector<JobRecord> list(std::optional<JobStatus> status, int limit, int offset,
                              const std::string& name = "");
  std::int64_t count(std::optional<JobStatus> status, const std::string& name = "");

  // Oldest queued job, now running (attempts + 1); none when the queue is empty.
  std::optional<JobRecord> claim_next();
  // Progress, optimiser checkpoint and the iteration's new trials (a JSON array) after an
  // iteration, in one transaction.
  void record_progress(const std::string& id, int iteration, std::int64_t evaluations,
                       double best_fitness, const nlohmann::json& best,
                       const std::string& checkpoint, const std::string& new_trials);
  std::optional<std::string> checkpoint(const std::string& id);
  // The trials recorded with the checkpoints so far: one JSON array per iteration, in order.
  std::vector<std::string> checkpoint_trials(const std::string& id);
  // Both of them read together (one consistent view), for a running job's partial results; the
  // iteration they are of. nullopt when the job has no checkpoint.
  struct Checkpoint {
    int iteration = -1;
    std::string optimizer;
    std::vector<std::string> trials;
  };
  std::optional<Checkpoint> checkpoint_with_trials(const std::string& id);

  // The final state; `finished_at` (UTC ISO 8601) is when the job ended, "" for now (a result
  // the store could not take at once is written later). `warnings`: how many its gains file has.
  void finish_succeeded(const std::string& id, const std::map<std::string, std::string>& artifacts,
                        const std::string& finished_at = "", int warnings = 0);
  void finish_failed(const std::string& id, const std::string& error,
                     const std::string& finished_at = "");
  // A cancelled job keeps the partial results of the iterations it ran (`artifacts`, may be
  // empty), stored with the status in one transaction.
  void finish_cancelled(const std::string& id, const std::string& finished_at = "",
                        const std::map<std::string, std::string>& artifacts = {});
  void requeue(const std::string& id);  // back to the queue, checkpoint kept
  // Queued: cancelled at once. Running: flagged, the worker stops after its iteration.
  // Returns the record after the change, or nullopt for an unknown id.
  std::optional<JobRecord> request_cancel(const std::string& id);
  bool cancel_requested(const std::string& id);
  // Removes a finished (succeeded, failed, cancelled) job and its files. A queued or running
  // job is not removed: it must be cancelled and stop first.
  enum class Removal { removed, not_found, active };
  Removal remove(const std::string& id);

  // At start-up: jobs left running by a crash go back to the queue, unless they have been started
  // `max_attempts` times already: a job that takes the server down each time it runs (or is
  // killed with it) would otherwise be retried forever. Those fail, with the reason.
  struct Recovery {
    int requeued = 0, failed = 0;
  };
  Recovery recover(int max_attempts);
  std::optional<std::string> artifact(const std::string& id, const std::string& name);
  // A small synced write that changes nothing else: whether the disk takes writes again.
  void probe();
  // The current time as the store writes it (UTC ISO 8601, milliseconds).
  static std::string timestamp();
  std::map<std::string, std::string> artifacts(const std::string& id);
  // The names and sizes of a job's artifacts, without their content.
  std::map<std::string, std::uint64_t> artifact_sizes(const std::string& id);
  // Adds or replaces one artifact of a finished job (a report rendered later).
  void put_artifact(const std::string& id, const std::string& name, const std::string& content);

 private:
  class Statement;
  void exec(const char* sql);
  // Both expect the caller to hold the lock (inside transaction() or get()).
  std::optional<JobRecord> select_job(const std::string& id);
  void set_finished(const std::string& id, JobStatus status, const std::string& error,
                    const std::string& finished_at = "");
  void insert_artifact(const std::string& id, const std::string& name, const std::string& content);
  template <class F>
  auto transaction(F&& body, bool synced = true);

  std::filesystem::path db_path_;
  int lock_fd_ = -1;
  sqlite3* db_ = nullptr;
  std::mutex mutex_;
};

}  // namespace ftc::tune
