#include "service/http_server.hpp"

#include <netdb.h>
#include <poll.h>
#include <spdlog/spdlog.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cstring>
#include <nlohmann/json.hpp>
#include <optional>

namespace ftc::tune::service_detail {

namespace {

using Clock = std::chrono::steady_clock;
using std::chrono::milliseconds;

// The longest single poll: a server that stops is noticed within this.
constexpr milliseconds kSlice{200};

void address_of(int sock, bool peer, std::string& ip, int& port) {
  sockaddr_storage a{};
  socklen_t len = sizeof a;
  const int rc = peer ? ::getpeername(sock, reinterpret_cast<sockaddr*>(&a), &len)
                      : ::getsockname(sock, reinterpret_cast<sockaddr*>(&a), &len);
  char host[NI_MAXHOST] = "";
  char serv[NI_MAXSERV] = "";
  if (rc != 0 || ::getnameinfo(reinterpret_cast<sockaddr*>(&a), len, host, sizeof host, serv,
                               sizeof serv, NI_NUMERICHOST | NI_NUMERICSERV) != 0) {
    ip.clear();
    port = -1;
    return;
  }
  ip = host;
  port = std::atoi(serv);
}

// A connection's socket as the library's parser reads it, with the header and body deadlines.
// Reads are buffered (the parser asks for one byte at a time while it reads lines).
class DeadlineStream final : public httplib::Stream {
 public:
  DeadlineStream(int sock, const ConnectionLimits& limits, const std::atomic<socket_t>& listener)
      : sock_(sock), limits_(limits), listener_(listener) {}

  // A new request: its header block is due within header_timeout from now.
  void start_request() {
    deadline_ = Clock::now() + limits_.header_timeout;
    timed_out_ = false;
    written_ = 0;
  }
  // Its headers have been read: the body is due within body_timeout from now.
  void start_body() { deadline_ = Clock::now() + limits_.body_timeout; }
  bool timed_out() const { return timed_out_; }
  bool wrote() const { return written_ > 0; }

  // Waits up to `timeout` for the first byte of the next request; false when the connection is
  // idle that long, closed, or the server stops.
  bool wait_for_request(milliseconds timeout) {
    if (pos_ < len_) return true;
    deadline_.reset();
    return wait(POLLIN, timeout, nullptr);
  }

  bool is_readable() const override {
    return pos_ < len_ || wait(POLLIN, limits_.read_timeout, &timed_out_);
  }
  bool is_writable() const override { return wait(POLLOUT, limits_.write_timeout, nullptr); }

  ssize_t read(char* ptr, size_t size) override {
    if (pos_ == len_) {
      if (!wait(POLLIN, limits_.read_timeout, &timed_out_)) return -1;
      ssize_t n;
      do n = ::recv(sock_, buf_, sizeof buf_, 0);
      while (n < 0 && errno == EINTR);
      if (n <= 0) return n;
      pos_ = 0;
      len_ = static_cast<std::size_t>(n);
    }
    const std::size_t n = std::min(size, len_ - pos_);
    std::memcpy(ptr, buf_ + pos_, n);
    pos_ += n;
    return static_cast<ssize_t>(n);
  }

  ssize_t write(const char* ptr, size_t size) override {
    if (!is_writable()) return -1;
    ssize_t n;
    do n = ::send(sock_, ptr, size, MSG_NOSIGNAL);
    while (n < 0 && errno == EINTR);
    if (n > 0) written_ += static_cast<std::size_t>(n);
    return n;
  }

  void get_remote_ip_and_port(std::string& ip, int& port) const override {
    address_of(sock_, true, ip, port);
  }
  void get_local_ip_and_port(std::string& ip, int& port) const override {
    address_of(sock_, false, ip, port);
  }
  socket_t socket() const override { return sock_; }

 private:
  // Polls for `events` up to `timeout`, cut at the request's deadline (which then sets
  // *expired) and given up when the server stops.
  bool wait(short events, milliseconds timeout, bool* expired) const {
    const Clock::time_point end = Clock::now() + timeout;
    for (;;) {
      if (listener_ == INVALID_SOCKET) return false;
      const Clock::time_point now = Clock::now();
      Clock::time_point until = end;
      if (expired && deadline_) {
        if (now >= *deadline_) {
          *expired = true;
          return false;
        }
        until = std::min(until, *deadline_);
      }
      if (now >= until) return false;
      const auto left = std::chrono::ceil<milliseconds>(until - now);
      pollfd p{sock_, events, 0};
      const int rc = ::poll(&p, 1, static_cast<int>(std::min(left, kSlice).count()));
      if (rc > 0) return true;
      if (rc < 0 && errno != EINTR) return false;
    }
  }

  int sock_;
  const ConnectionLimits& limits_;
  const std::atomic<socket_t>& listener_;
  std::optional<Clock::time_point> deadline_;
  mutable bool timed_out_ = false;
  std::size_t written_ = 0;
  char buf_[4096];
  std::size_t pos_ = 0, len_ = 0;
};

thread_local const DeadlineStream* t_stream = nullptr;

// An answer written straight to a socket the parser never read from (or gave up on).
void send_error(int sock, int status, const char* reason, const char* code,
                const std::string& message, const char* retry_after) {
  const std::string body =
      nlohmann::json{
          {"error", {{"code", code}, {"message", message}, {"details", nlohmann::json::array()}}}}
          .dump();
  std::string r = std::string("HTTP/1.1 ")
                      .append(std::to_string(status))
                      .append(" ")
                      .append(reason)
                      .append("\r\nContent-Type: application/json\r\nContent-Length: ")
                      .append(std::to_string(body.size()))
                      .append("\r\nConnection: close\r\n")
                      // The headers every other answer carries (api.cpp's post-routing handler).
                      .append("X-Content-Type-Options: nosniff\r\n")
                      .append("Content-Security-Policy: default-src 'none'; frame-ancestors 'none'\r\n");
  if (retry_after) r.append("Retry-After: ").append(retry_after).append("\r\n");
  r.append("\r\n").append(body);
  // A fresh socket's send buffer takes this whole; a client that does not read is not waited for.
  (void)::send(sock, r.data(), r.size(), MSG_NOSIGNAL | MSG_DONTWAIT);
}

// Closes after an answer the client may not have read yet: closing a socket with unread input
// resets the connection, and the reset can overtake the answer. So: end our side, read away
// what the client still sends for a moment, then close.
void linger_and_close(int sock) {
  ::shutdown(sock, SHUT_WR);
  const Clock::time_point end = Clock::now() + milliseconds(100);
  char buf[4096];
  for (Clock::time_point now = Clock::now(); now < end; now = Clock::now()) {
    pollfd p{sock, POLLIN, 0};
    if (::poll(&p, 1, static_cast<int>(std::chrono::ceil<milliseconds>(end - now).count())) <= 0)
      break;
    if (::recv(sock, buf, sizeof buf, MSG_DONTWAIT) <= 0) break;
  }
  ::close(sock);
}

std::string seconds_text(milliseconds ms) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g s", static_cast<double>(ms.count()) / 1000.0);
  return buf;
}

}  // namespace

GuardedServer::GuardedServer(const ConnectionLimits& limits) : limits_(limits) {
  const std::size_t threads = static_cast<std::size_t>(std::max(1, limits.threads));
  new_task_queue = [threads] { return new httplib::ThreadPool(threads); };
  // Answers go out at once: with Nagle's algorithm a reply's last segment waits for the ACK of
  // the one before, which the client delays, so every request after the first on a kept-alive
  // connection (the dashboard's) took about 40 ms.
  set_tcp_nodelay(true);
}

bool GuardedServer::request_timed_out() { return t_stream && t_stream->timed_out(); }

bool GuardedServer::peer_closed() {
  if (!t_stream) return false;
  pollfd p{t_stream->socket(), POLLIN | POLLRDHUP, 0};
  if (::poll(&p, 1, 0) <= 0) return false;
  if (p.revents & (POLLRDHUP | POLLHUP | POLLERR)) return true;
  char c;
  return ::recv(p.fd, &c, 1, MSG_PEEK | MSG_DONTWAIT) == 0;
}

bool GuardedServer::process_and_close_socket(socket_t sock) {
  std::string ip;
  int port = 0;
  address_of(sock, true, ip, port);
  int open = 0;
  {
    std::lock_guard<std::mutex> lock(clients_mutex_);
    open = clients_[ip];
    if (open < limits_.per_client) ++clients_[ip];
  }
  if (open >= limits_.per_client) {
    spdlog::warn("{} has {} connections open already: one more refused", ip, open);
    send_error(sock, 429, "Too Many Requests", "too_many_connections",
               "this address has " + std::to_string(open) +
                   " connections open to the server, the most it serves per client "
                   "(--max-connections-per-client): close one, or wait for one to end",
               "1");
    linger_and_close(sock);
    return false;
  }

  bool ret = false;
  {
    DeadlineStream stream(sock, limits_, svr_sock_);
    t_stream = &stream;
    for (std::size_t left = limits_.requests_per_connection; left > 0; --left) {
      if (!stream.wait_for_request(limits_.idle_timeout)) break;
      stream.start_request();
      bool closed = false;
      ret = process_request(stream, left == 1, closed, [&stream](httplib::Request& req) {
        stream.start_body();
        // RFC 9112 §6.3: a request with neither Content-Length nor Transfer-Encoding has no
        // body. cpp-httplib would read one until the client closes (and answer a POST /cancel
        // or a PUT without a body with 400 once the deadline passed): say so explicitly.
        if (!req.has_header("Content-Length") && !req.has_header("Transfer-Encoding"))
          req.headers.emplace("Content-Length", "0");
      });
      if (stream.timed_out()) {
        // The parser gives up without an answer when the request line itself is late.
        if (!stream.wrote())
          send_error(sock, 408, "Request Timeout", "request_timeout",
                     "the request's headers did not arrive within " +
                         seconds_text(limits_.header_timeout) + " of its first byte",
                     nullptr);
        spdlog::warn("{}: a request ran past its deadline; connection closed", ip);
        ret = false;
      }
      if (!ret || closed) break;
    }
    t_stream = nullptr;
  }
  {
    std::lock_guard<std::mutex> lock(clients_mutex_);
    if (--clients_[ip] <= 0) clients_.erase(ip);
  }
  linger_and_close(sock);
  return ret;
}

}  // namespace ftc::tune::service_detail
