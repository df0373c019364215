#pragma once
// Live updates for the dashboard: one notifier that the store's writers (the runner after each
// iteration's commit, the API after a submission, cancellation or deletion) publish to, and that
// every open event stream (GET /v1/events) waits on. A change is read from the store once, by
// the publisher, and fanned out to all streams: a stream never queries SQLite. Private to
// tuner/service.
#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <map>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

namespace ftc::tune::service_detail {

struct Event {
  std::uint64_t seq = 0;
  std::string job_id;  // the job it is about
  std::string text;    // "id: …\nevent: …\ndata: …\n\n", as sent
};

class EventHub {
 public:
  // Keeps the last `backlog` events for streams that are behind; at most `max_streams` open,
  // and at most `max_per_client` of them from one client address (0: no such limit).
  explicit EventHub(std::size_t max_streams, std::size_t max_per_client = 0,
                    std::size_t backlog = 1024)
      : max_streams_(max_streams), max_per_client_(max_per_client), backlog_(backlog) {}

  // Sends `data` (JSON on one line) as an event of type `type` about job `job_id`.
  void publish(const std::string& type, const std::string& job_id, const std::string& data);
  // Wakes every stream and refuses new ones: the server stops.
  void close();
  std::size_t open_streams();
  std::size_t max_streams() const { return max_streams_; }
  std::size_t max_per_client() const { return max_per_client_; }

  // A stream's place in the events; its slot is freed on destruction.
  class Stream {
   public:
    Stream(Stream&& o) noexcept : hub_(o.hub_), next_(o.next_), client_(std::move(o.client_)) {
      o.hub_ = nullptr;
    }
    Stream(const Stream&) = delete;
    Stream& operator=(const Stream&) = delete;
    Stream& operator=(Stream&&) = delete;
    ~Stream();
    // The events after the last ones returned, waiting up to `timeout_ms` for one; empty after
    // the timeout. nullopt once the hub has closed. A stream more than the backlog behind skips
    // to the oldest event kept.
    std::optional<std::vector<Event>> next(int timeout_ms);

   private:
    friend class EventHub;
    Stream(EventHub* hub, std::uint64_t next, std::string client)
        : hub_(hub), next_(next), client_(std::move(client)) {}
    EventHub* hub_;
    std::uint64_t next_;  // seq of the next event to deliver
    std::string client_;  // the address it was opened from
  };
  // Why open() gave no stream.
  enum class Refused { full, client_full, closed };
  // A stream of the events from now on for a client at address `client`; nullopt (and why)
  // when `max_streams` are open, the client has its limit open (`limit` when > 0, else
  // `max_per_client`), or the hub closed. A client "" is not counted per client: only
  // `max_streams` bounds its streams.
  std::optional<Stream> open(const std::string& client = "", Refused* why = nullptr,
                             std::size_t limit = 0);

 private:
  std::mutex mutex_;
  std::condition_variable changed_;
  std::deque<Event> events_;  // the last backlog_ events, oldest first
  std::uint64_t seq_ = 0;     // of the last event published
  std::size_t streams_ = 0;
  std::map<std::string, std::size_t> per_client_;  // open streams by client address (none: 0)
  bool closed_ = false;
  std::size_t max_streams_, max_per_client_, backlog_;
};

}  // namespace ftc::tune::service_detail
