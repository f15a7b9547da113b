#include "clients/dashboard/guarded_server.h"

#include <netdb.h>
#include <poll.h>
#include <sys/eventfd.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>

#include "clients/dashboard/api_json.h"

namespace mpdrig::dashboard {

using Clock = std::chrono::steady_clock;

struct GuardedServer::Connection {
  int fd = -1;
  std::string in;  // received and not yet parsed: the next request, and any pipelined after it
  Clock::time_point deadline;
  bool in_request = false;        // the next request's first byte has arrived: the request deadline
  bool draining = false;          // refused and answered: what still arrives is discarded until EOF
  bool fresh = false;             // back from a worker with bytes buffered: inspect them at once
  std::size_t request_bytes = 0;  // the complete request's head and declared body
  std::size_t discarded = 0;
  int served = 0;
};

namespace {

constexpr std::size_t kMaxDrainBytes = 1 << 20;  // discarded after a refusal, at most
constexpr double kDrainS = 1.0;                  // ... and for at most this long

Clock::duration Seconds(double s) {
  return std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(s));
}

// The task queue httplib's accept loop hands each socket to: at once, on that thread, since
// process_and_close_socket only queues it for the poller.
class InlineQueue final : public httplib::TaskQueue {
 public:
  void enqueue(std::function<void()> fn) override { fn(); }
  void shutdown() override {}
};

void CloseSocket(int fd) {
  shutdown(fd, SHUT_RDWR);
  close(fd);
}

const char* Reason(int status) {
  switch (status) {
    case 400:
      return "Bad Request";
    case 408:
      return "Request Timeout";
    case 411:
      return "Length Required";
    case 413:
      return "Payload Too Large";
    case 431:
      return "Request Header Fields Too Large";
    default:
      return "Service Unavailable";
  }
}

// A refusal the poller writes itself (the request never reaches httplib): small enough for the
// socket's send buffer, so it is written without waiting or not at all.
void SendRefusal(int fd, int status, const std::string& message) {
  const std::string body = ErrorJson(message);
  char head[256];
  std::snprintf(head, sizeof head,
                "HTTP/1.1 %d %s\r\nContent-Type: application/json\r\nContent-Length: %zu\r\n"
                "Cache-Control: no-store\r\nConnection: close\r\n\r\n",
                status, Reason(status), body.size());
  const std::string answer = head + body;
  [[maybe_unused]] ssize_t sent =
      send(fd, answer.data(), answer.size(), MSG_DONTWAIT | MSG_NOSIGNAL);
}

bool WaitFor(int fd, short events, Clock::time_point deadline) {
  for (;;) {
    const auto left =
        std::chrono::duration_cast<std::chrono::milliseconds>(deadline - Clock::now());
    if (left.count() < 0) return false;
    pollfd p{fd, events, 0};
    const int n = poll(&p, 1, static_cast<int>(left.count()) + 1);
    if (n > 0) return true;
    if (n < 0 && errno != EINTR) return false;
  }
}

void Address(int fd, bool peer, std::string& ip, int& port) {
  sockaddr_storage address{};
  socklen_t length = sizeof address;
  const int got = peer ? getpeername(fd, reinterpret_cast<sockaddr*>(&address), &length)
                       : getsockname(fd, reinterpret_cast<sockaddr*>(&address), &length);
  char host[NI_MAXHOST] = "";
  char service[NI_MAXSERV] = "";
  if (got != 0 || getnameinfo(reinterpret_cast<sockaddr*>(&address), length, host, sizeof host,
                              service, sizeof service, NI_NUMERICHOST | NI_NUMERICSERV) != 0) {
    ip.clear();
    port = 0;
    return;
  }
  ip = host;
  port = std::atoi(service);
}

// httplib's view of a connection while a worker answers one request: reads come from what the
// poller buffered (the whole request, unless the client asked "Expect: 100-continue", whose body
// is read here within the request's deadline and the body limit); writes wait at most `write_s`.
class ConnectionStream final : public httplib::Stream {
 public:
  static constexpr std::size_t kFlushBytes = 64 * 1024;

  ConnectionStream(GuardedServer::Connection* connection, const ServerLimits& limits)
      : connection_(connection), limits_(limits), body_left_(limits.max_body_bytes) {}

  bool is_readable() const override {
    return used_ < connection_->in.size() || WaitFor(connection_->fd, POLLIN, Clock::now());
  }
  bool is_writable() const override {
    return WaitFor(connection_->fd, POLLOUT, Clock::now() + Seconds(limits_.write_s));
  }

  ssize_t read(char* ptr, size_t size) override {
    const std::string& in = connection_->in;
    if (used_ < in.size()) {
      const std::size_t n = std::min(size, in.size() - used_);
      std::memcpy(ptr, in.data() + used_, n);
      used_ += n;
      return static_cast<ssize_t>(n);
    }
    // Only a body after "Expect: 100-continue" is read here: the client waits for the 100.
    if (!Flush() || body_left_ == 0 || !WaitFor(connection_->fd, POLLIN, connection_->deadline)) {
      failed_ = true;
      return -1;
    }
    const ssize_t n = recv(connection_->fd, ptr, std::min(size, body_left_), 0);
    if (n <= 0) {
      failed_ = true;
      return n < 0 ? -1 : 0;
    }
    body_left_ -= static_cast<std::size_t>(n);
    direct_ += static_cast<std::size_t>(n);
    return n;
  }

  // An answer goes out in one send where it fits (httplib writes the head and the body apart:
  // two small sends on a kept-alive connection would meet Nagle and the delayed ACK, 40 ms).
  ssize_t write(const char* ptr, size_t size) override {
    out_.append(ptr, size);
    if (out_.size() >= kFlushBytes && !Flush()) return -1;
    return static_cast<ssize_t>(size);
  }

  // Sends what write() gathered, waiting at most `write_s`; false if it could not.
  bool Flush() {
    const auto deadline = Clock::now() + Seconds(limits_.write_s);
    std::size_t done = 0;
    while (done < out_.size() && !failed_) {
      const ssize_t n = send(connection_->fd, out_.data() + done, out_.size() - done,
                             MSG_DONTWAIT | MSG_NOSIGNAL);
      if (n > 0) {
        done += static_cast<std::size_t>(n);
      } else if (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK || errno == EINTR)) {
        if (!WaitFor(connection_->fd, POLLOUT, deadline)) failed_ = true;
      } else {
        failed_ = true;
      }
    }
    out_.clear();
    return !failed_;
  }

  void get_remote_ip_and_port(std::string& ip, int& port) const override {
    Address(connection_->fd, true, ip, port);
  }
  void get_local_ip_and_port(std::string& ip, int& port) const override {
    Address(connection_->fd, false, ip, port);
  }
  socket_t socket() const override { return connection_->fd; }

  std::size_t used() const { return used_; }      // from the buffer
  std::size_t direct() const { return direct_; }  // from the socket

  bool failed() const { return failed_; }

 private:
  GuardedServer::Connection* connection_;
  const ServerLimits& limits_;
  std::size_t used_ = 0;
  std::size_t direct_ = 0;
  std::size_t body_left_;
  std::string out_;
  bool failed_ = false;
};

std::string Lower(std::string text) {
  for (char& c : text) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return text;
}

// What the poller makes of a connection's buffer.
struct Verdict {
  enum Kind { kNeedMore, kComplete, kRefuse } kind = kNeedMore;
  int status = 0;
  std::string message;
  std::size_t request_bytes = 0;  // kComplete: head and declared body
};

Verdict Refuse(int status, std::string message) {
  return {Verdict::kRefuse, status, std::move(message)};
}

// Is the buffered request complete (head, and the body its Content-Length declares)? Only what
// the limits need is read here; httplib parses the request itself.
Verdict Inspect(std::string* buffer, const ServerLimits& limits) {
  const std::string& in = *buffer;
  const std::size_t end = in.find("\r\n\r\n");
  if (end == std::string::npos || end + 4 > limits.max_head_bytes) {
    if (in.size() <= limits.max_head_bytes) return {};
    return Refuse(431, "the request line and headers exceed " +
                           std::to_string(limits.max_head_bytes) + " bytes");
  }
  const std::size_t head_bytes = end + 4;
  const std::string method = in.substr(0, in.find(' '));
  bool length_given = false;
  bool chunked = false;
  bool expect_continue = false;
  std::uint64_t length = 0;
  std::size_t at = in.find("\r\n") + 2;
  while (at < end) {
    const std::size_t eol = in.find("\r\n", at);
    const std::string line = in.substr(at, eol - at);
    at = eol + 2;
    const std::size_t colon = line.find(':');
    if (colon == std::string::npos) continue;
    const std::string name = Lower(line.substr(0, colon));
    std::string value = line.substr(colon + 1);
    value.erase(0, value.find_first_not_of(" \t"));
    value.erase(value.find_last_not_of(" \t") + 1);
    if (name == "transfer-encoding") {
      chunked = true;
    } else if (name == "expect") {
      expect_continue = Lower(value) == "100-continue";
    } else if (name == "content-length") {
      if (value.empty() || value.size() > 19 ||
          value.find_first_not_of("0123456789") != std::string::npos)
        return Refuse(400, "Content-Length '" + value.substr(0, 32) + "' is not a number");
      const std::uint64_t parsed = std::strtoull(value.c_str(), nullptr, 10);
      if (length_given && parsed != length) return Refuse(400, "two different Content-Lengths");
      length = parsed;
      length_given = true;
    }
  }
  const std::string limit = std::to_string(limits.max_body_bytes);
  if (chunked)
    return Refuse(411, "a request body must come with a Content-Length (at most " + limit +
                           " bytes), not in chunks");
  if (length > limits.max_body_bytes)
    return Refuse(413, "a request body of " + std::to_string(length) +
                           " bytes is more than the dashboard takes (" + limit + " bytes)");
  const bool takes_body = method == "POST" || method == "PUT" || method == "PATCH" ||
                          method == "DELETE" || method == "PRI";
  // No length and no chunks: no body (RFC 9112 6.3). httplib would read one until EOF instead,
  // so the request gets the length it means.
  if (takes_body && !length_given) {
    const std::string zero = "Content-Length: 0\r\n";
    buffer->insert(end + 2, zero);
    return {Verdict::kComplete, 0, {}, head_bytes + zero.size()};
  }
  if (expect_continue || in.size() >= head_bytes + length)
    return {Verdict::kComplete, 0, {}, head_bytes + static_cast<std::size_t>(length)};
  return {};
}

}  // namespace

GuardedServer::GuardedServer(const ServerLimits& limits) : limits_(limits) {
  new_task_queue = [] { return new InlineQueue; };
  // httplib's default also sets SO_REUSEPORT, with which a second dashboard on the same port
  // would start "fine" and take half the connections: only SO_REUSEADDR (a restart may bind at
  // once), so that a port in use is an error.
  set_socket_options([](socket_t sock) {
    int yes = 1;
    setsockopt(sock, SOL_SOCKET, SO_REUSEADDR, &yes, sizeof yes);
  });
  // httplib's own settings, for what it writes (the Keep-Alive header) and reads itself.
  set_keep_alive_max_count(static_cast<std::size_t>(limits_.max_requests_per_connection));
  set_keep_alive_timeout(static_cast<time_t>(limits_.idle_s));
  set_read_timeout(Seconds(limits_.request_s));
  set_write_timeout(Seconds(limits_.write_s));
  set_payload_max_length(limits_.max_body_bytes);
  wake_fd_ = eventfd(0, EFD_CLOEXEC | EFD_NONBLOCK);
  if (wake_fd_ < 0) {
    std::perror("dashboard: eventfd");
    std::abort();
  }
  poller_ = std::thread(&GuardedServer::Poll, this);
  for (int i = 0; i < limits_.workers; ++i) workers_.emplace_back(&GuardedServer::Work, this);
}

GuardedServer::~GuardedServer() {
  StopConnections();
  close(wake_fd_);
}

int GuardedServer::Bind(const std::string& host, int port) {
  const int bound = port == 0 ? bind_to_any_port(host) : (bind_to_port(host, port) ? port : -1);
  // httplib listens with a backlog of 5: a burst of connections (a page's parallel fetches
  // beside many others) would wait for SYN retries. Listening again only widens the backlog.
  if (bound > 0) ::listen(svr_sock_, 128);
  return bound;
}

void GuardedServer::StopConnections() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (stopping_ && !poller_.joinable()) return;
    stopping_ = true;
  }
  work_ready_.notify_all();
  Wake();
  if (poller_.joinable()) poller_.join();
  for (auto& worker : workers_)
    if (worker.joinable()) worker.join();
  std::lock_guard<std::mutex> lock(mutex_);
  for (auto& connection : incoming_) CloseSocket(connection->fd);
  for (auto& connection : ready_) CloseSocket(connection->fd);
  incoming_.clear();
  ready_.clear();
}

void GuardedServer::Wake() {
  const std::uint64_t one = 1;
  [[maybe_unused]] ssize_t n = ::write(wake_fd_, &one, sizeof one);
}

bool GuardedServer::process_and_close_socket(socket_t sock) {
  auto connection = std::make_unique<Connection>();
  connection->fd = sock;
  connection->deadline = Clock::now() + Seconds(limits_.idle_s);
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (!stopping_ && open_connections_ < limits_.max_connections) {
      ++open_connections_;
      incoming_.push_back(std::move(connection));
      Wake();
      return true;
    }
  }
  SendRefusal(sock, 503,
              "the dashboard has " + std::to_string(limits_.max_connections) +
                  " connections open; try again");
  CloseSocket(sock);
  return false;
}

bool GuardedServer::ReadAvailable(Connection* connection) {
  // Never more than one request can need: the head and the largest body (and what comes with
  // them). A full buffer holds a complete request, which a worker takes before more is read.
  const std::size_t cap = limits_.max_head_bytes + limits_.max_body_bytes + 4096;
  char chunk[16384];
  while (connection->in.size() < cap) {
    const std::size_t room = std::min(sizeof chunk, cap - connection->in.size());
    const ssize_t n = recv(connection->fd, chunk, room, MSG_DONTWAIT);
    if (n > 0) {
      connection->in.append(chunk, static_cast<std::size_t>(n));
      continue;
    }
    if (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK)) return true;
    if (n < 0 && errno == EINTR) continue;
    return false;  // EOF or an error
  }
  return true;
}

void GuardedServer::Poll() {
  std::vector<std::unique_ptr<Connection>> connections;
  std::vector<pollfd> fds;
  std::vector<std::unique_ptr<Connection>> to_workers;
  for (;;) {
    auto now = Clock::now();
    {
      std::lock_guard<std::mutex> lock(mutex_);
      if (stopping_) break;
      for (auto& connection : incoming_) connections.push_back(std::move(connection));
      incoming_.clear();
    }
    fds.assign(1, pollfd{wake_fd_, POLLIN, 0});
    auto first_deadline = Clock::time_point::max();
    for (const auto& connection : connections) {
      fds.push_back(pollfd{connection->fd, POLLIN, 0});
      first_deadline = std::min(first_deadline, connection->fresh ? now : connection->deadline);
    }
    int timeout_ms = -1;
    if (first_deadline != Clock::time_point::max()) {
      const auto left =
          std::chrono::duration_cast<std::chrono::milliseconds>(first_deadline - now).count();
      timeout_ms = static_cast<int>(std::clamp<long long>(left + 1, 0, 60'000));
    }
    if (poll(fds.data(), fds.size(), timeout_ms) < 0 && errno != EINTR) {
      std::perror("dashboard: poll");
      break;
    }
    if (fds[0].revents != 0) {
      std::uint64_t count = 0;
      [[maybe_unused]] ssize_t n = ::read(wake_fd_, &count, sizeof count);
    }
    now = Clock::now();
    int closed = 0;
    for (std::size_t i = 0; i < connections.size(); ++i) {
      Connection* connection = connections[i].get();
      const bool readable = (fds[i + 1].revents & (POLLIN | POLLHUP | POLLERR)) != 0;
      bool keep = true;
      bool complete = false;
      if (connection->draining) {
        char sink[16384];
        const ssize_t n = readable ? recv(connection->fd, sink, sizeof sink, MSG_DONTWAIT) : -1;
        if (n > 0) connection->discarded += static_cast<std::size_t>(n);
        keep = !(readable && n == 0) && !(n < 0 && readable && errno != EAGAIN) &&
               connection->discarded < kMaxDrainBytes && now < connection->deadline;
      } else {
        if (readable) keep = ReadAvailable(connection);
        // Only what changed is inspected: new bytes, or a connection back from a worker that
        // may hold the next request already (pipelining).
        if (keep && (readable || connection->fresh) && !connection->in.empty()) {
          if (!connection->in_request) {
            connection->in_request = true;
            connection->deadline = now + Seconds(limits_.request_s);
          }
          const Verdict verdict = Inspect(&connection->in, limits_);
          if (verdict.kind == Verdict::kComplete) {
            complete = true;
            connection->request_bytes = verdict.request_bytes;
          } else if (verdict.kind == Verdict::kRefuse) {
            SendRefusal(connection->fd, verdict.status, verdict.message);
            shutdown(connection->fd, SHUT_WR);
            connection->draining = true;
            connection->in.clear();
            connection->deadline = now + Seconds(kDrainS);
          }
        }
        if (keep && !complete && !connection->draining && now >= connection->deadline) {
          if (connection->in_request) {
            SendRefusal(connection->fd, 408,
                        "the request did not arrive within " +
                            std::to_string(static_cast<int>(limits_.request_s)) + " s");
          }
          keep = false;  // a silent connection past its idle time closes without a word
        }
      }
      connection->fresh = false;
      if (!keep) {
        CloseSocket(connection->fd);
        connections[i].reset();
        ++closed;
      } else if (complete) {
        to_workers.push_back(std::move(connections[i]));
      }
    }
    connections.erase(std::remove(connections.begin(), connections.end(), nullptr),
                      connections.end());
    if (closed > 0 || !to_workers.empty()) {
      std::lock_guard<std::mutex> lock(mutex_);
      open_connections_ -= closed;
      for (auto& connection : to_workers) ready_.push_back(std::move(connection));
    }
    if (!to_workers.empty()) {
      to_workers.clear();
      work_ready_.notify_all();
    }
  }
  for (auto& connection : connections) CloseSocket(connection->fd);
}

void GuardedServer::Work() {
  for (;;) {
    std::unique_ptr<Connection> connection;
    {
      std::unique_lock<std::mutex> lock(mutex_);
      work_ready_.wait(lock, [this] { return stopping_ || !ready_.empty(); });
      if (stopping_) return;
      connection = std::move(ready_.front());
      ready_.pop_front();
    }
    Serve(std::move(connection));
  }
}

void GuardedServer::Serve(std::unique_ptr<Connection> connection) {
  ConnectionStream stream(connection.get(), limits_);
  const bool last = connection->served + 1 >= limits_.max_requests_per_connection;
  bool connection_closed = false;
  const bool answered = process_request(stream, last, connection_closed, nullptr) && stream.Flush();
  ++connection->served;
  // A body httplib did not read (a write refused before its body, a GET with one) is dropped
  // here, not taken for the next request; one still on its way ("Expect: 100-continue" refused)
  // closes the connection.
  const std::size_t end = connection->request_bytes;
  bool body_to_come = false;
  if (stream.used() + stream.direct() >= end)
    connection->in.erase(0, stream.used());
  else if (connection->in.size() + stream.direct() >= end)
    connection->in.erase(0, end - stream.direct());
  else
    body_to_come = true;
  if (!answered || connection_closed || last || stream.failed() || body_to_come) {
    CloseSocket(connection->fd);
    std::lock_guard<std::mutex> lock(mutex_);
    --open_connections_;
    return;
  }
  connection->in_request = false;
  connection->fresh = !connection->in.empty();
  connection->deadline = Clock::now() + Seconds(limits_.idle_s);
  ToPoller(std::move(connection));
}

void GuardedServer::ToPoller(std::unique_ptr<Connection> connection) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (stopping_) {
      CloseSocket(connection->fd);
      --open_connections_;
      return;
    }
    incoming_.push_back(std::move(connection));
  }
  Wake();
}

}  // namespace mpdrig::dashboard
