#include "service/job_runner.hpp"

#include <spdlog/spdlog.h>

#include <chrono>
#include <cstdio>
#include <nlohmann/json.hpp>

#include "ftc/tune/job/job.hpp"
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

bool JobRunner::cancel_deferred(const std::string& id) {
  std::lock_guard<std::mutex> lock(held_mutex_);
  return cancels_.count(id) > 0;
}

void JobRunner::write(const std::string& id, Held& h) {
  try {
    switch (h.state.status) {
      case JobStatus::succeeded:
        store_.finish_succeeded(id, h.files, h.state.finished_at);
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

std::map<std::string, std::string> JobRunner::partial_files(
    const std::string& id, TuningOutcome& r, BatchEvaluator& evaluator,
    std::chrono::steady_clock::time_point t0) {
  if (r.optimization.history.empty()) return {};
  try {
    compare_best(r, evaluator, opt_.trajectory_rows);
    std::map<std::string, std::string> files = output_files(r);
    json run = run_metadata(
        r, std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
    run["job_id"] = id;
    run["completed"] = false;
    files["run.json"] = run.dump(2) + "\n";
    std::uint64_t bytes = 0;
    for (const auto& [name, content] : files) bytes += content.size();
    if (bytes > opt_.max_stored_bytes) {
      spdlog::warn("job {}: its partial results take {}, above the limit of {}: not kept", id,
                   megabytes(bytes), megabytes(opt_.max_stored_bytes));
      return {};
    }
    spdlog::info("job {}: the results of its {} iteration(s) are kept, marked partial", id,
                 r.optimization.history.size());
    return files;
  } catch (const std::exception& e) {
    spdlog::warn("job {}: its partial results could not be made: {}", id, e.what());
    return {};
  }
}

void JobRunner::run(const JobRecord& rec) {
  const std::string& id = rec.id;
  const auto t0 = std::chrono::steady_clock::now();
  Held outcome;
  const auto failed = [&](const std::string& why) {
    outcome = Held{{JobStatus::failed, why, JobStore::timestamp(), 0}, {}};
  };
  try {
    const Job job = parse_job_text(store_.job_json(id), "job " + id);
    std::vector<std::string> names;
    for (const ParameterBounds& b : job.tuning->parameters) names.push_back(b.name);
    const std::optional<std::string> checkpoint = store_.checkpoint(id);
    json state;
    RunOptions ro;
    ro.max_trajectory_rows = opt_.trajectory_rows;
    std::size_t stored_trials = 0;
    std::uint64_t trial_bytes = 0;  // of the trials checkpointed so far
    if (checkpoint) {
      // The optimiser's state, with the trials recorded beside it.
      json trials = json::array();
      for (const std::string& rows : store_.checkpoint_trials(id)) {
        trial_bytes += rows.size();
        for (json& t : json::parse(rows)) trials.push_back(std::move(t));
      }
      stored_trials = trials.size();
      state = {{"optimizer", json::parse(*checkpoint)}, {"trials", std::move(trials)}};
      ro.resume = &state;
      spdlog::info("job {} resumes after iteration {} (attempt {})", id, rec.iteration,
                   rec.attempts);
    } else {
      spdlog::info("job {} ({}) started", id, rec.name);
    }
    std::string too_large;
    ro.observer = [&](const HistoryRow& h, const Optimizer& o, const std::vector<Trial>& trials) {
      json best = json::object();
      for (std::size_t i = 0; i < names.size() && i < h.best.size(); ++i)
        best[names[i]] = h.best[i];
      const std::string rows = trials_json(trials, stored_trials).dump();
      const std::string optimizer = o.state().dump();
      const std::uint64_t bytes = trial_bytes + rows.size() + optimizer.size();
      if (bytes > opt_.max_stored_bytes) {
        too_large = "its checkpoint (the optimiser's state and the trials so far) reached " +
                    megabytes(bytes) + " after iteration " + std::to_string(h.iteration) +
                    ", above the server's limit of " + megabytes(opt_.max_stored_bytes) +
                    " per job (--max-stored-mib): ask for fewer evaluations";
        return false;
      }
      try {
        store_.record_progress(id, h.iteration, h.evaluations, h.best_fitness, best, optimizer,
                               rows);
        store_wrote();
        changed(id);
        stored_trials = trials.size();
        trial_bytes += rows.size();
      } catch (const StoreError& e) {
        if (!e.transient()) throw;
        // The run goes on: the next checkpoint carries these trials too, and a crash meanwhile
        // resumes from the last one stored.
        store_failed(e);
      }
      return !stopping_ && !store_.cancel_requested(id) && !cancel_deferred(id);
    };
    const std::unique_ptr<BatchEvaluator> evaluator = make_evaluator_();
    TuningOutcome r = tune(job, *evaluator, ro);
    if (!too_large.empty()) {
      failed(too_large);
    } else if (store_.cancel_requested(id) || cancel_deferred(id)) {
      outcome = Held{{JobStatus::cancelled, "", "", 0}, partial_files(id, r, *evaluator, t0)};
      for (const auto& [name, content] : outcome.files) outcome.state.bytes += content.size();
      outcome.state.finished_at = JobStore::timestamp();
    } else if (!r.completed()) {
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
      std::map<std::string, std::string> files = output_files(r);
      const double wall =
          std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      json run = run_metadata(r, wall);
      run["job_id"] = id;
      run["started_at"] = rec.started_at;
      run["attempts"] = rec.attempts;
      files["run.json"] = run.dump(2) + "\n";
      std::uint64_t bytes = 0;
      for (const auto& [name, content] : files) bytes += content.size();
      if (bytes > opt_.max_stored_bytes) {
        failed("its results take " + megabytes(bytes) + ", above the server's limit of " +
               megabytes(opt_.max_stored_bytes) +
               " per job (--max-stored-mib): ask for fewer evaluations, scenarios or compared "
               "controllers");
      } else {
        outcome = Held{{JobStatus::succeeded, "", JobStore::timestamp(), bytes}, std::move(files)};
        spdlog::info("job {} succeeded in {:.2f} s: J = {:.6g}", id, wall,
                     r.optimization.best_fitness);
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
