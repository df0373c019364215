#include "service/job_runner.hpp"

#include <spdlog/spdlog.h>

#include <chrono>
#include <cstdio>
#include <limits>
#include <nlohmann/json.hpp>

#include "ftc/tune/job/job.hpp"
#include "ftc/tune/api/api.hpp"
#include "ftc/tune/run/documents.hpp"
#include "ftc/tune/run/tuning_run.hpp"

namespace ftc::tune::service_detail {

using nlohmann::json;

namespace {

std::string megabytes(std::uint64_t bytes) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.1f MB", static_cast<double>(bytes) / 1e6);
  return buf;
}

// The job store as a run's storage (api/api.hpp): the run API's run_job() tunes the job as
// `ftctune run` does and hands its checkpoints and files here. A checkpoint is the optimiser's
// state with only the iteration's new trials (record_progress, O(trials) in all), refused past
// the job's byte limit (which stops the run); the files are kept for the runner, which stores
// them with the job's final state in one transaction (held in memory while the store cannot
// write).
class JobStoreStorage final : public RunStorage {
 public:
  JobStoreStorage(JobStore& store, const JobRecord& rec, std::uint64_t max_bytes,
                  std::function<void()> wrote, std::function<void(const StoreError&)> failed,
                  std::function<void()> changed)
      : store_(store),
        rec_(rec),
        max_bytes_(max_bytes),
        wrote_(std::move(wrote)),
        failed_(std::move(failed)),
        changed_(std::move(changed)) {}

  std::string checkpoint_name() const override { return "job " + rec_.id + "'s checkpoint"; }
  std::optional<Checkpoint> load_checkpoint(const std::string&, std::uint64_t) override {
    const std::optional<std::string> optimizer = store_.checkpoint(rec_.id);
    if (!optimizer) {
      spdlog::info("job {} ({}) started", rec_.id, rec_.name);
      return std::nullopt;
    }
    // The optimiser's state, with the trials recorded beside it.
    json trials = json::array();
    for (const std::string& rows : store_.checkpoint_trials(rec_.id)) {
      trial_bytes_ += rows.size();
      for (json& t : json::parse(rows)) trials.push_back(std::move(t));
    }
    stored_trials_ = trials.size();
    spdlog::info("job {} resumes after iteration {} (attempt {})", rec_.id, rec_.iteration,
                 rec_.attempts);
    return Checkpoint{rec_.iteration,
                      json{{"optimizer", json::parse(*optimizer)}, {"trials", std::move(trials)}}};
  }
  bool save_checkpoint(const std::string&, std::uint64_t, const HistoryRow& h, const Optimizer& o,
                       const std::vector<Trial>& trials) override {
    json best = json::object();
    double best_fitness = h.best_fitness;
    if (front_) {
      // A front has no single best (the row's is one corner of it): its size so far. (Not its
      // hypervolume: against the reference point of the front so far, which moves as the
      // front does, the figure could fall while the front improves; history.csv's is against
      // the final front's reference.)
      best = {{"front", {{"points", front_points_}}}};
      best_fitness = std::numeric_limits<double>::quiet_NaN();
    } else {
      for (std::size_t i = 0; i < names_.size() && i < h.best.size(); ++i)
        best[names_[i]] = h.best[i];
    }
    const std::string rows = trials_json(trials, stored_trials_).dump();
    const std::string optimizer = o.state().dump();
    const std::uint64_t bytes = trial_bytes_ + rows.size() + optimizer.size();
    if (bytes > max_bytes_) {
      too_large = "its checkpoint (the optimiser's state and the trials so far) reached " +
                  megabytes(bytes) + " after iteration " + std::to_string(h.iteration) +
                  ", above the server's limit of " + megabytes(max_bytes_) +
                  " per job (--max-stored-mib): ask for fewer evaluations";
      return false;
    }
    try {
      store_.record_progress(rec_.id, h.iteration, h.evaluations, best_fitness, best, optimizer,
                             rows);
      wrote_();
      changed_();
      stored_trials_ = trials.size();
      trial_bytes_ += rows.size();
    } catch (const StoreError& e) {
      if (!e.transient()) throw;
      // The run goes on: the next checkpoint carries these trials too, and a crash meanwhile
      // resumes from the last one stored.
      failed_(e);
    }
    return true;
  }
  void front_so_far(std::size_t points) override { front_points_ = points; }
  void describe(json& run) const override {
    // Not a file: the job's id, when it first started and how often.
    run.erase("job_file");
    run["job_id"] = rec_.id;
    run["started_at"] = rec_.started_at;
    run["attempts"] = rec_.attempts;
  }
  void put(const RunJobResult&, const std::map<std::string, std::string>& made) override {
    files = made;
  }

  // The job the run tunes: its parameters' names, and whether the progress records a front.
  void name_parameters(const Job& job) {
    for (const ParameterBounds& b : job.tuning->parameters) names_.push_back(b.name);
    front_ = front_objectives(job) >= 2;
  }

  std::string too_large;                      // why the run was stopped, if its checkpoint was
  std::map<std::string, std::string> files;  // put(): the run's files

 private:
  JobStore& store_;
  const JobRecord& rec_;
  std::uint64_t max_bytes_;
  std::function<void()> wrote_;
  std::function<void(const StoreError&)> failed_;
  std::function<void()> changed_;
  std::vector<std::string> names_;
  bool front_ = false;            // a job with two or more soft goals
  std::size_t front_points_ = 0;  // its front's size so far (front_so_far)
  std::size_t stored_trials_ = 0;
  std::uint64_t trial_bytes_ = 0;  // of the trials checkpointed so far
};

}  // namespace

void JobRunner::start() {
  for (int i = 0; i < opt_.workers; ++i) threads_.emplace_back([this] { worker_loop(); });
}

void JobRunner::notify() {
  {
    std::lock_guard<std::mutex> lock(wake_mutex_);
    ++submissions_;
  }
  wake_.notify_one();
}

void JobRunner::stop() {
  {
    std::lock_guard<std::mutex> lock(wake_mutex_);
    stopping_ = true;
  }
  wake_.notify_all();
  const bool had_workers = !threads_.empty();
  for (std::thread& w : threads_)
    if (w.joinable()) w.join();
  threads_.clear();
  if (!had_workers || flush()) return;
  // What is left is not lost for good: the store still shows these jobs running (or queued), so
  // the next start runs them again from their last checkpoint.
  std::lock_guard<std::mutex> lock(held_mutex_);
  for (const auto& [id, h] : held_)
    spdlog::error(
        "job {} ({}) finished, but the store could not take its results before the server "
        "stopped ({}); the next start runs it again from its last checkpoint",
        id, to_string(h.state.status), store_error_.value_or("?"));
  for (const std::string& id : cancels_)
    spdlog::error(
        "job {}: its cancellation could not be recorded before the server stopped; "
        "cancel it again after the next start",
        id);
}

void JobRunner::store_wrote() {
  std::lock_guard<std::mutex> lock(held_mutex_);
  if (held_.empty() && cancels_.empty()) store_error_.reset();
}

void JobRunner::note_failure(const StoreError& e) {
  if (!store_error_) spdlog::warn("the job store cannot write: {}", e.what());
  store_error_ = e.what();
}

void JobRunner::store_failed(const StoreError& e) {
  std::lock_guard<std::mutex> lock(held_mutex_);
  note_failure(e);
}

StoreHealth JobRunner::health() {
  std::lock_guard<std::mutex> lock(held_mutex_);
  return {store_error_, held_.size(), cancels_.size()};
}

std::optional<Unstored> JobRunner::unstored(const std::string& id) {
  std::lock_guard<std::mutex> lock(held_mutex_);
  const auto it = held_.find(id);
  if (it == held_.end()) return std::nullopt;
  return it->second.state;
}

std::optional<JobStatus> JobRunner::cancel_unstored(const std::string& id) {
  std::lock_guard<std::mutex> lock(held_mutex_);
  const auto it = held_.find(id);
  if (it == held_.end()) return std::nullopt;
  Held& h = it->second;
  const JobStatus was = h.state.status;
  if (was == JobStatus::succeeded) {
    h.state.status = JobStatus::cancelled;
    h.state.bytes = 0;
    h.files.clear();
  }
  return was;
}

void JobRunner::defer_cancel(const std::string& id) {
  std::lock_guard<std::mutex> lock(held_mutex_);
  cancels_.insert(id);
}

void JobRunner::interrupt(const std::string& id) {
  std::lock_guard<std::mutex> lock(running_mutex_);
  if (const auto it = running_.find(id); it != running_.end()) it->second->store(true);
}

bool JobRunner::cancel_deferred(const std::string& id) {
  std::lock_guard<std::mutex> lock(held_mutex_);
  return cancels_.count(id) > 0;
}

void JobRunner::write(const std::string& id, Held& h) {
  try {
    switch (h.state.status) {
      case JobStatus::succeeded:
        store_.finish_succeeded(id, h.files, h.state.finished_at, h.state.warnings);
        break;
      case JobStatus::cancelled:
        store_.finish_cancelled(id, h.state.finished_at, h.files);
        break;
      default:
        store_.finish_failed(id, h.state.error, h.state.finished_at);
        break;
    }
  } catch (const StoreError& e) {
    if (e.transient()) throw;
    // The store will never take these files (SQLite refuses them): the job fails with the
    // reason rather than being retried.
    spdlog::error("job {}: cannot store its final state: {}", id, e.what());
    if (h.state.status == JobStatus::cancelled && !h.files.empty()) {
      // Cancelled all the same, without its partial results.
      h.files.clear();
      h.state.bytes = 0;
      write(id, h);
      return;
    }
    if (h.state.status != JobStatus::succeeded) return;
    h = Held{{JobStatus::failed, std::string("its results could not be stored: ").append(e.what()),
              h.state.finished_at, 0},
             {}};
    write(id, h);
    return;
  }
  if (h.state.status == JobStatus::succeeded)
    spdlog::info("job {} stored: {} of results", id, megabytes(h.state.bytes));
}

bool JobRunner::flush() {
  // Told after the lock is released: the API's view of a job asks for it too.
  std::vector<std::string> written;
  const bool ok = [&] {
    std::lock_guard<std::mutex> lock(held_mutex_);
    if (!store_error_ && held_.empty() && cancels_.empty()) return true;
    try {
      const bool owed = !held_.empty() || !cancels_.empty();
      for (auto it = cancels_.begin(); it != cancels_.end(); it = cancels_.erase(it)) try {
          store_.request_cancel(*it);
          written.push_back(*it);
          spdlog::info("job {}: the cancellation held in memory is recorded", *it);
        } catch (const StoreError& e) {
          if (e.transient()) throw;
          spdlog::error("job {}: cannot record its cancellation: {}", *it, e.what());
        }
      for (auto it = held_.begin(); it != held_.end(); it = held_.erase(it)) {
        write(it->first, it->second);
        written.push_back(it->first);
      }
      // Nothing was owed, only a write refused: is there room again?
      if (!owed) store_.probe();
    } catch (const StoreError& e) {
      note_failure(e);
      return false;
    }
    spdlog::info("the job store writes again");
    store_error_.reset();
    return true;
  }();
  for (const std::string& id : written) changed(id);
  return ok;
}

void JobRunner::worker_loop() {
  const auto retry = std::chrono::duration_cast<std::chrono::milliseconds>(
      std::chrono::duration<double>(opt_.retry_seconds));
  while (!stopping_) {
    std::uint64_t seen;
    {
      std::lock_guard<std::mutex> lock(wake_mutex_);
      seen = submissions_;
    }
    // What the store owes is written before any new job starts.
    const bool clear = flush();
    std::optional<JobRecord> job;
    if (clear) try {
        job = store_.claim_next();
        if (job) {
          store_wrote();
          changed(job->id);
        }
      } catch (const StoreError& e) {
        if (e.transient())
          store_failed(e);
        else
          spdlog::error("cannot read the queue: {}", e.what());
      } catch (const std::exception& e) {
        spdlog::error("cannot read the queue: {}", e.what());
      }
    if (!job) {
      // Sleep until a submission newer than our look at the queue (none is missed: `seen`
      // was read before claim_next), the retry time, or stop.
      std::unique_lock<std::mutex> lock(wake_mutex_);
      wake_.wait_for(lock, clear ? std::chrono::milliseconds(1000) : retry,
                     [&] { return stopping_.load() || (clear && submissions_ != seen); });
      continue;
    }
    run(*job);
  }
}

void JobRunner::run(const JobRecord& rec) {
  const std::string& id = rec.id;
  Held outcome;
  const auto failed = [&](const std::string& why) {
    outcome = Held{{JobStatus::failed, why, JobStore::timestamp(), 0}, {}};
  };
  const auto cancelled = [&] { return store_.cancel_requested(id) || cancel_deferred(id); };
  const auto bytes_of = [](const std::map<std::string, std::string>& files) {
    std::uint64_t bytes = 0;
    for (const auto& [name, content] : files) bytes += content.size();
    return bytes;
  };
  try {
    const Job job = parse_job_text(store_.job_json(id), "job " + id);
    JobStoreStorage storage(
        store_, rec, opt_.max_stored_bytes, [this] { store_wrote(); },
        [this](const StoreError& e) { store_failed(e); }, [this, &id] { changed(id); });
    storage.name_parameters(job);
    const std::unique_ptr<BatchEvaluator> evaluator = make_evaluator_();
    // The run API's run, as `ftctune run` runs it, into the store.
    RunJobOptions ro;
    ro.job_file = "job " + id;
    ro.storage = &storage;
    ro.evaluator = evaluator.get();
    ro.checkpoint = CheckpointPolicy::every_iteration;
    ro.max_trajectory_rows = opt_.trajectory_rows;
    ro.on_iteration = [&](const IterationReport&) { return !stopping_ && !cancelled(); };
    // Within an iteration, a cancel through this server: before the next pack. (A stopping
    // server still lets the iteration end and checkpoints it, so that a job whose iteration is
    // longer than the server's runs between restarts still gets on.)
    const auto flag = std::make_shared<std::atomic<bool>>(false);
    struct Running {
      JobRunner& runner;
      const std::string& id;
      ~Running() {
        std::lock_guard<std::mutex> lock(runner.running_mutex_);
        runner.running_.erase(id);
      }
    } running{*this, id};
    {
      std::lock_guard<std::mutex> lock(running_mutex_);
      running_[id] = flag;
    }
    // A cancel that came between the claim and now.
    if (cancelled()) flag->store(true);
    ro.interrupt = [flag] { return flag->load(std::memory_order_relaxed); };
    // A cancelled job keeps its results so far (a stopping server's job goes back to the queue).
    ro.keep_partial = [&] { return storage.too_large.empty() && cancelled(); };
    ro.log = [&id](LogLevel level, const std::string& message) {
      if (level == LogLevel::warn)
        spdlog::warn("job {}: {}", id, message);
      else
        spdlog::debug("job {}: {}", id, message);
    };
    const RunJobResult r = run_job(job, ro);
    if (!storage.too_large.empty()) {
      failed(storage.too_large);
    } else if (cancelled()) {
      // Stopped after an iteration (its partial results), or finished as the cancel came.
      std::map<std::string, std::string> files;
      if (bytes_of(storage.files) > opt_.max_stored_bytes)
        spdlog::warn("job {}: its partial results take {}, above the limit of {}: not kept", id,
                     megabytes(bytes_of(storage.files)), megabytes(opt_.max_stored_bytes));
      else
        files = std::move(storage.files);
      if (!files.empty())
        spdlog::info("job {}: the results of its {} iteration(s) are kept, marked partial", id,
                     r.outcome.optimization.history.size());
      outcome = Held{{JobStatus::cancelled, "", JobStore::timestamp(), bytes_of(files)},
                     std::move(files)};
    } else if (r.stopped) {
      try {
        store_.requeue(id);
        spdlog::info("job {} checkpointed and put back in the queue", id);
        changed(id);
      } catch (const StoreError& e) {
        // Still running in the store: the next start puts it back in the queue anyway.
        spdlog::warn("job {}: cannot put it back in the queue ({}); the next start will", id,
                     e.what());
      }
      return;
    } else {
      const std::uint64_t bytes = bytes_of(storage.files);
      if (bytes > opt_.max_stored_bytes) {
        failed("its results take " + megabytes(bytes) + ", above the server's limit of " +
               megabytes(opt_.max_stored_bytes) +
               " per job (--max-stored-mib): ask for fewer evaluations, scenarios or compared "
               "controllers");
      } else {
        outcome = Held{{JobStatus::succeeded, "", JobStore::timestamp(), bytes,
                        static_cast<int>(r.outcome.warnings.size())},
                       std::move(storage.files)};
        spdlog::info("job {} succeeded in {:.2f} s: J = {:.6g}", id, r.wall_seconds,
                     r.outcome.optimization.best_fitness);
      }
    }
  } catch (const std::exception& e) {
    failed(e.what());
  }
  if (outcome.state.status == JobStatus::failed)
    spdlog::error("job {} failed: {}", id, outcome.state.error);
  else if (outcome.state.status == JobStatus::cancelled)
    spdlog::info("job {} cancelled", id);
  bool stored = false;
  try {
    write(id, outcome);
    stored = true;
    changed(id);
  } catch (const StoreError& e) {
    store_failed(e);
  } catch (const std::exception& e) {
    // Left running in the store: the next start runs it again.
    spdlog::error("job {}: cannot store its final state: {}", id, e.what());
    return;
  }
  std::lock_guard<std::mutex> lock(held_mutex_);
  const bool cancel_came = cancels_.erase(id) > 0;
  if (stored) {
    if (held_.empty() && cancels_.empty()) store_error_.reset();
    return;
  }
  spdlog::warn(
      "job {} finished ({}), but the store cannot take it yet: kept in memory, tried "
      "again every {} s and before the next job",
      id, to_string(outcome.state.status), opt_.retry_seconds);
  // A cancellation that came while it finished wins, as it would have a moment earlier.
  if (cancel_came && outcome.state.status == JobStatus::succeeded)
    outcome = Held{{JobStatus::cancelled, "", outcome.state.finished_at, 0}, {}};
  held_.emplace(id, std::move(outcome));
}

}  // namespace ftc::tune::service_detail
