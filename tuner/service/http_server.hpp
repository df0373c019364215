#pragma once
// cpp-httplib's server with the defences against slow and greedy clients that 0.11.4 lacks. The
// library times each wait for bytes (5 s) but not a request as a whole, so a client sending a
// header line every 2 s held a thread for as long as it liked, and a dozen of them took every
// thread of its pool. This server serves each connection itself (the library's per-connection
// entry point is virtual; its request parser is reused as is) over a stream that enforces:
//   - a deadline for a request's whole header block, from its first byte, and one for its body,
//     from the end of the headers; a request past either gets 408 and its connection is closed;
//   - at most `per_client` connections from one address at a time: the next ones are answered
//     429 and closed as soon as a thread takes them, before any of their bytes is waited for;
//   - `threads` connections served at once (the library's default pool has 8).
// Private to tuner/service.
#include <chrono>
#include <cstddef>
#include <map>
#include <mutex>
#include <string>

#include "service/httplib.hpp"

namespace ftc::tune::service_detail {

struct ConnectionLimits {
  std::chrono::milliseconds header_timeout{10000};
  std::chrono::milliseconds body_timeout{60000};
  std::chrono::milliseconds read_timeout{5000};   // any one wait for bytes
  std::chrono::milliseconds write_timeout{5000};  // any one wait to send
  std::chrono::milliseconds idle_timeout{5000};   // for the next request on a connection
  std::size_t requests_per_connection = 5;
  int per_client = 16;
  int threads = 64;
};

class GuardedServer : public httplib::Server {
 public:
  explicit GuardedServer(const ConnectionLimits& limits);
  // Whether the request served on the calling thread ran past its header or body deadline (a
  // read of it failed for that reason).
  static bool request_timed_out();
  // Whether the client of the request served on the calling thread has closed its connection:
  // a long answer (an event stream) stops then instead of at its next write.
  static bool peer_closed();

 private:
  bool process_and_close_socket(socket_t sock) override;

  ConnectionLimits limits_;
  std::mutex clients_mutex_;
  std::map<std::string, int> clients_;  // open connections per peer address
};

}  // namespace ftc::tune::service_detail
