#include "service/events.hpp"

#include <chrono>

namespace ftc::tune::service_detail {

void EventHub::publish(const std::string& type, const std::string& job_id,
                       const std::string& data) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (closed_) return;
    Event e;
    e.seq = ++seq_;
    e.job_id = job_id;
    e.text = "id: " + std::to_string(e.seq) + "\nevent: " + type + "\ndata: " + data + "\n\n";
    events_.push_back(std::move(e));
    while (events_.size() > backlog_) events_.pop_front();
  }
  changed_.notify_all();
}

void EventHub::close() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    closed_ = true;
  }
  changed_.notify_all();
}

std::size_t EventHub::open_streams() {
  std::lock_guard<std::mutex> lock(mutex_);
  return streams_;
}

std::optional<EventHub::Stream> EventHub::open(const std::string& client, Refused* why,
                                               std::size_t limit) {
  std::lock_guard<std::mutex> lock(mutex_);
  const auto refuse = [&](Refused r) {
    if (why) *why = r;
    return std::nullopt;
  };
  if (closed_) return refuse(Refused::closed);
  if (!client.empty()) {
    const auto it = per_client_.find(client);
    const std::size_t cap = limit > 0 ? limit : max_per_client_;
    if (cap > 0 && it != per_client_.end() && it->second >= cap)
      return refuse(Refused::client_full);
  }
  if (streams_ >= max_streams_) return refuse(Refused::full);
  ++streams_;
  if (!client.empty()) ++per_client_[client];
  return Stream(this, seq_ + 1, client);
}

EventHub::Stream::~Stream() {
  if (!hub_) return;
  std::lock_guard<std::mutex> lock(hub_->mutex_);
  --hub_->streams_;
  if (client_.empty()) return;  // not counted per client
  // A client with no stream left holds no entry: the map is as large as the open streams.
  const auto it = hub_->per_client_.find(client_);
  if (it != hub_->per_client_.end() && --it->second == 0) hub_->per_client_.erase(it);
}

std::optional<std::vector<Event>> EventHub::Stream::next(int timeout_ms) {
  std::unique_lock<std::mutex> lock(hub_->mutex_);
  hub_->changed_.wait_for(lock, std::chrono::milliseconds(timeout_ms),
                          [&] { return hub_->closed_ || hub_->seq_ >= next_; });
  if (hub_->closed_) return std::nullopt;
  std::vector<Event> out;
  for (const Event& e : hub_->events_)
    if (e.seq >= next_) out.push_back(e);
  next_ = hub_->seq_ + 1;
  return out;
}

}  // namespace ftc::tune::service_detail
