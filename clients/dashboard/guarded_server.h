// The dashboard's HTTP server: cpp-httplib's request parsing, routing and responses, with the
// connections run here so that no client can hold the server (Debian 12's cpp-httplib 0.11.4
// gives each connection a pool thread for its whole life: 8 clients sending a header line every
// 2 s blocked it, as did 200 idle connections, and a 200 MB body was read into memory).
//
// A connection costs a thread only while its request is answered:
//   - One poller thread waits on every open connection (poll(2)) and reads each request into the
//     connection's buffer, without blocking, until its head (request line and headers) is
//     complete and, if it declares a Content-Length within `max_body_bytes`, its body too. Only
//     then does a worker take it, parse it, route it and write the answer. Slow and idle clients
//     cost a poll slot each, never a worker.
//   - Deadlines: a connection silent for `idle_s` (before its first request, or between two) is
//     closed; a request whose head and body have not all arrived `request_s` after its first
//     byte gets 408 and is closed, however steadily it trickles.
//   - Bounds: a head over `max_head_bytes` gets 431; a body over `max_body_bytes` gets 413 as soon
//     as its head has arrived, without its body being read (the rest is discarded, not kept); a
//     chunked body gets 411 (a write must say its length); a POST with neither has no body. At most
//     `max_connections` are open: the next is answered 503 at once and closed. A connection serves
//     at most `max_requests_per_connection` requests.
// Every refusal is a JSON body {"ok":false,"error":...} and closes the connection.
#pragma once

#include <chrono>
#include <condition_variable>
#include <cstddef>
#include <deque>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include <httplib.h>

namespace mpdrig::dashboard {

struct ServerLimits {
  std::size_t max_head_bytes = 16 * 1024;  // request line and headers
  std::size_t max_body_bytes = 64 * 1024;  // the page's writes carry none; 64 KiB is plenty
  double request_s = 5.0;                  // from a request's first byte to its last
  double idle_s = 5.0;                     // keep-alive: silence before, and between, requests
  double write_s = 5.0;       // an answer the client does not read for this long is dropped
  int workers = 4;            // threads that route requests and write answers
  int max_connections = 400;  // open connections (an idle one costs a poll slot, no thread)
  int max_requests_per_connection = 100;
};

class GuardedServer final : public httplib::Server {
 public:
  explicit GuardedServer(const ServerLimits& limits);
  ~GuardedServer() override;
  GuardedServer(const GuardedServer&) = delete;
  GuardedServer& operator=(const GuardedServer&) = delete;

  // bind_to_port, or bind_to_any_port for port 0, with a listen backlog of 128 instead of
  // httplib's 5. Returns the port, or -1.
  int Bind(const std::string& host, int port);

  // Closes every connection and joins the threads (after listen_after_bind has returned).
  void StopConnections();

  const ServerLimits& limits() const { return limits_; }

  struct Connection;

 private:
  // httplib's accept loop hands each accepted socket here (on its own thread: the task queue
  // runs this at once, as it only queues the socket for the poller).
  bool process_and_close_socket(socket_t sock) override;

  void Poll();
  void Work();
  // Reads what has arrived; false when the connection is to be closed (EOF, error, a refusal).
  bool ReadAvailable(Connection* connection);
  void Serve(std::unique_ptr<Connection> connection);
  void ToPoller(std::unique_ptr<Connection> connection);
  void Wake();

  const ServerLimits limits_;
  int wake_fd_ = -1;  // eventfd: a connection for the poller, or stop

  std::mutex mutex_;
  std::condition_variable work_ready_;
  bool stopping_ = false;
  int open_connections_ = 0;
  std::vector<std::unique_ptr<Connection>> incoming_;  // for the poller
  std::deque<std::unique_ptr<Connection>> ready_;      // complete requests, for the workers

  std::thread poller_;
  std::vector<std::thread> workers_;
};

}  // namespace mpdrig::dashboard
