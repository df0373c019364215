#include "service/job_runner.hpp"

#include <spdlog/spdlog.h>

#include <chrono>
#include <nlohmann/json.hpp>

#include "ftc/tune/job/job.hpp"
#include "ftc/tune/run/documents.hpp"
#include "ftc/tune/run/tuning_run.hpp"

namespace ftc::tune::service_detail {

using nlohmann::json;

void JobRunner::start() {
  for (int i = 0; i < workers_; ++i) threads_.emplace_back([this] { worker_loop(); });
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
  for (std::thread& w : threads_)
    if (w.joinable()) w.join();
  threads_.clear();
}

void JobRunner::worker_loop() {
  while (!stopping_) {
    std::uint64_t seen;
    {
      std::lock_guard<std::mutex> lock(wake_mutex_);
      seen = submissions_;
    }
    std::optional<JobRecord> job;
    try {
      job = store_.claim_next();
    } catch (const std::exception& e) {
      spdlog::error("cannot read the queue: {}", e.what());
    }
    if (!job) {
      // Sleep until a submission newer than our look at the queue (none is missed: `seen`
      // was read before claim_next), or stop.
      std::unique_lock<std::mutex> lock(wake_mutex_);
      wake_.wait_for(lock, std::chrono::seconds(1),
                     [&] { return stopping_.load() || submissions_ != seen; });
      continue;
    }
    run(*job);
  }
}

void JobRunner::run(const JobRecord& rec) {
  const std::string& id = rec.id;
  const auto t0 = std::chrono::steady_clock::now();
  try {
    const Job job = parse_job_text(store_.job_json(id), "job " + id);
    std::vector<std::string> names;
    for (const ParameterBounds& b : job.tuning->parameters) names.push_back(b.name);
    const std::optional<std::string> checkpoint = store_.checkpoint(id);
    json state;
    RunOptions ro;
    std::size_t stored_trials = 0;
    if (checkpoint) {
      // The optimiser's state, with the trials recorded beside it.
      json trials = json::array();
      for (const std::string& rows : store_.checkpoint_trials(id))
        for (json& t : json::parse(rows)) trials.push_back(std::move(t));
      stored_trials = trials.size();
      state = {{"optimizer", json::parse(*checkpoint)}, {"trials", std::move(trials)}};
      ro.resume = &state;
      spdlog::info("job {} resumes after iteration {} (attempt {})", id, rec.iteration,
                   rec.attempts);
    } else {
      spdlog::info("job {} ({}) started", id, rec.name);
    }
    ro.observer = [&](const HistoryRow& h, const Optimizer& o, const std::vector<Trial>& trials) {
      json best = json::object();
      for (std::size_t i = 0; i < names.size() && i < h.best.size(); ++i)
        best[names[i]] = h.best[i];
      store_.record_progress(id, h.iteration, h.evaluations, h.best_fitness, best, o.state().dump(),
                             trials_json(trials, stored_trials).dump());
      stored_trials = trials.size();
      return !stopping_ && !store_.cancel_requested(id);
    };
    const std::unique_ptr<BatchEvaluator> evaluator = make_evaluator_();
    const TuningOutcome r = tune(job, *evaluator, ro);
    if (store_.cancel_requested(id)) {
      store_.finish_cancelled(id);
      spdlog::info("job {} cancelled", id);
    } else if (!r.completed()) {
      store_.requeue(id);
      spdlog::info("job {} checkpointed and put back in the queue", id);
    } else {
      std::map<std::string, std::string> files = output_files(r);
      const double wall =
          std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      json run = run_metadata(r, wall);
      run["job_id"] = id;
      run["started_at"] = rec.started_at;
      run["attempts"] = rec.attempts;
      files["run.json"] = run.dump(2) + "\n";
      store_.finish_succeeded(id, files);
      spdlog::info("job {} succeeded in {:.2f} s: J = {:.6g}", id, wall,
                   r.optimization.best_fitness);
    }
  } catch (const std::exception& e) {
    spdlog::error("job {} failed: {}", id, e.what());
    try {
      store_.finish_failed(id, e.what());
    } catch (const std::exception& e2) {
      spdlog::error("job {}: cannot record the failure: {}", id, e2.what());
    }
  }
}

}  // namespace ftc::tune::service_detail
