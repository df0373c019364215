#pragma once
// The service's workers: each takes the oldest queued job from the store, tunes it with the same
// tuner as `ftctune run`, checkpoints the optimiser after every iteration and stores the result
// files with the job's final status. Private to tuner/service.
#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <thread>
#include <vector>

#include "ftc/tune/evaluators/batch_evaluator.hpp"
#include "ftc/tune/service/job_store.hpp"

namespace ftc::tune::service_detail {

class JobRunner {
 public:
  using EvaluatorFactory = std::function<std::unique_ptr<BatchEvaluator>()>;

  JobRunner(JobStore& store, int workers, EvaluatorFactory make_evaluator)
      : store_(store), workers_(workers), make_evaluator_(std::move(make_evaluator)) {}
  ~JobRunner() { stop(); }

  void start();
  // A job was queued: wake a worker.
  void notify();
  // Running jobs checkpoint at the end of their iteration and go back to the queue; returns
  // when every worker has stopped. Idempotent.
  void stop();

 private:
  void worker_loop();
  void run(const JobRecord& rec);

  JobStore& store_;
  int workers_;
  EvaluatorFactory make_evaluator_;
  std::vector<std::thread> threads_;
  std::atomic<bool> stopping_{false};
  std::mutex wake_mutex_;
  std::condition_variable wake_;
  std::uint64_t submissions_ = 0;  // bumped under wake_mutex_ on every submission
};

}  // namespace ftc::tune::service_detail
