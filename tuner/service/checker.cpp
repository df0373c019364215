#include "service/checker.hpp"

#include <utility>

namespace ftc::tune::service_detail {

Checker::Checker() : worker_([this] { loop(); }) {}

Checker::~Checker() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
  }
  wake_.notify_all();
  worker_.join();
}

void Checker::loop() {
  std::unique_lock<std::mutex> lock(mutex_);
  for (;;) {
    wake_.wait(lock, [this] { return stop_ || !queue_.empty(); });
    if (stop_) return;
    const std::shared_ptr<Task> task = std::move(queue_.front());
    queue_.pop_front();
    if (task->abandoned) {
      ++skipped_;
      continue;
    }
    running_ = true;
    lock.unlock();
    try {
      task->work();
    } catch (...) {
      task->error = std::current_exception();
    }
    lock.lock();
    running_ = false;
    task->done = true;
    done_.notify_all();
  }
}

Checker::Outcome Checker::run(std::function<void()> work,
                              std::chrono::steady_clock::time_point deadline,
                              const std::function<bool()>& client_left,
                              std::chrono::milliseconds poll) {
  auto task = std::make_shared<Task>();
  task->work = std::move(work);
  std::unique_lock<std::mutex> lock(mutex_);
  queue_.push_back(task);
  wake_.notify_one();
  for (;;) {
    const auto until = std::min(deadline, std::chrono::steady_clock::now() + poll);
    if (done_.wait_until(lock, until, [&] { return task->done; })) break;
    Outcome gave_up;
    if (std::chrono::steady_clock::now() >= deadline) {
      gave_up = Outcome::timed_out;
    } else {
      lock.unlock();
      const bool left = client_left();
      lock.lock();
      if (task->done) break;
      if (!left) continue;
      gave_up = Outcome::client_left;
    }
    task->abandoned = true;
    ++abandoned_;
    return gave_up;
  }
  if (task->error) std::rethrow_exception(task->error);
  return Outcome::done;
}

Checker::Counts Checker::counts() const {
  std::lock_guard<std::mutex> lock(mutex_);
  Counts c;
  for (const auto& t : queue_) c.queued += t->abandoned ? 0 : 1;
  c.running = running_;
  c.abandoned = abandoned_;
  c.skipped = skipped_;
  return c;
}

}  // namespace ftc::tune::service_detail
