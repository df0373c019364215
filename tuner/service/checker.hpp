#pragma once
// Where the service checks submitted jobs (POST /v1/jobs, POST /v1/validate): one worker thread
// that parses and checks one body at a time, so that however many large or broken bodies
// arrive at once, checking them takes at most one core from the running jobs (three 100 KB
// bodies checked at once on the request threads slowed a running job from 25 s to 42 s).
//
// A request waits for its turn and its check up to a deadline. A request that gives up (the
// deadline passed, or the client hung up) abandons its check: one still waiting is never run,
// and one already running finishes (checking is linear in the body, about 1.5 s for a 1 MiB
// body of 250 000 broken scenarios) and its answer is dropped. Private to tuner/service.
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <exception>
#include <functional>
#include <memory>
#include <mutex>
#include <thread>

namespace ftc::tune::service_detail {

class Checker {
 public:
  // One check: the work, run on the worker once, and what the asking request needs to know.
  struct Task {
    std::function<void()> work;
    std::exception_ptr error;  // what `work` threw, rethrown to the asking request
    bool done = false;         // guarded by the checker's mutex
    bool abandoned = false;    // likewise
  };
  struct Counts {
    std::int64_t queued = 0;     // waiting for the worker (not abandoned)
    bool running = false;        // the worker is checking a body
    std::int64_t abandoned = 0;  // since start: given up by their requests
    std::int64_t skipped = 0;    // since start: of those, never run
  };
  enum class Outcome { done, timed_out, client_left };

  Checker();
  ~Checker();
  Checker(const Checker&) = delete;
  Checker& operator=(const Checker&) = delete;

  // Runs `work` on the worker and waits for it until `deadline`. Every `poll` it asks
  // `client_left`; when that says yes, or the deadline passes, the work is abandoned: `work`
  // must own what it reads and writes (it may run after this returns). What `work` throws is
  // rethrown here.
  Outcome run(std::function<void()> work, std::chrono::steady_clock::time_point deadline,
              const std::function<bool()>& client_left,
              std::chrono::milliseconds poll = std::chrono::milliseconds(50));

  Counts counts() const;

 private:
  void loop();

  mutable std::mutex mutex_;
  std::condition_variable wake_;  // the worker: a task arrived, or stop
  std::condition_variable done_;  // the requests: a task finished
  std::deque<std::shared_ptr<Task>> queue_;
  bool running_ = false;
  bool stop_ = false;
  std::int64_t abandoned_ = 0, skipped_ = 0;
  std::thread worker_;
};

}  // namespace ftc::tune::service_detail
