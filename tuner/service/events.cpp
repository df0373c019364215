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

std::optional<EventHub::Stream> EventHub::open() {
  std::lock_guard<std::mutex> lock(mutex_);
  if (closed_ || streams_ >= max_streams_) return std::nullopt;
  ++streams_;
  return Stream(this, seq_ + 1);
}

EventHub::Stream::~Stream() {
  if (!hub_) return;
  std::lock_guard<std::mutex> lock(hub_->mutex_);
  --hub_->streams_;
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
