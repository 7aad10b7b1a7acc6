#include "api/line_server.hpp"

#include <arpa/inet.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstring>
#include <stdexcept>
#include <vector>

#include "uavsim/common/tcp_socket.hpp"

namespace uavsim::server::api {

namespace {

constexpr double kOverloadGrace_s = 5.0;  // an overloaded peer that reads nothing is closed after this

void set_nonblocking(int fd) { fcntl(fd, F_SETFL, fcntl(fd, F_GETFL, 0) | O_NONBLOCK); }

double steady_now_s() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

int open_spare_fd() { return open("/dev/null", O_RDONLY | O_CLOEXEC); }

}  // namespace

LineServer::LineServer(const std::string& bind_address, uint16_t port, Limits limits, Callbacks callbacks)
    : callbacks_(std::move(callbacks)), limits_(std::move(limits)), max_line_bytes_(limits_.max_line_bytes) {
  const std::string where = bind_address + ":" + std::to_string(port);
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_port = htons(port);
  if (inet_pton(AF_INET, bind_address.c_str(), &addr.sin_addr) != 1) {
    throw std::runtime_error("sim API: bad bind address '" + bind_address + "' (an IPv4 address)");
  }
  listen_fd_ = socket(AF_INET, SOCK_STREAM, 0);
  const int one = 1;
  setsockopt(listen_fd_, SOL_SOCKET, SO_REUSEADDR, &one, sizeof(one));
  if (listen_fd_ < 0 || bind(listen_fd_, reinterpret_cast<sockaddr*>(&addr), sizeof(addr)) != 0 ||
      listen(listen_fd_, 16) != 0) {
    const std::string error = std::strerror(errno);
    if (listen_fd_ >= 0) close(listen_fd_);
    throw std::runtime_error("sim API: cannot listen on " + where + ": " + error);
  }
  socklen_t len = sizeof(addr);
  getsockname(listen_fd_, reinterpret_cast<sockaddr*>(&addr), &len);
  port_ = ntohs(addr.sin_port);
  set_nonblocking(listen_fd_);
  if (pipe(wake_fds_) != 0) throw std::runtime_error("sim API: cannot create the wake-up pipe");
  set_nonblocking(wake_fds_[0]);
  set_nonblocking(wake_fds_[1]);
  spare_fd_ = open_spare_fd();
}

LineServer::~LineServer() {
  stop();
  for (auto& [id, c] : conns_) close(c.fd);
  if (listen_fd_ >= 0) close(listen_fd_);
  if (spare_fd_ >= 0) close(spare_fd_);
  close(wake_fds_[0]);
  close(wake_fds_[1]);
}

void LineServer::start() { thread_ = std::thread([this] { run(); }); }

void LineServer::stop() {
  stop_ = true;
  wake();
  if (thread_.joinable()) thread_.join();
}

void LineServer::wake() {
  // output is queued before wake() is called, and the I/O thread clears the flag before it looks at
  // the queues: a wake-up skipped here finds its output in that look
  if (wake_pending_.exchange(true)) return;
  const char b = 1;
  [[maybe_unused]] ssize_t n = write(wake_fds_[1], &b, 1);  // full pipe: a wake-up is pending anyway
}

void LineServer::mark_overloaded(Conn& c) {
  if (c.overloaded) return;
  c.overloaded = true;
  c.overloaded_at_s = steady_now_s();
  c.out += limits_.overload_line;
  total_pending_ += limits_.overload_line.size();
}

bool LineServer::send(uint64_t conn, const std::string& data) {
  {
    std::lock_guard<std::mutex> lock(out_mutex_);
    auto it = conns_.find(conn);
    if (it == conns_.end()) return false;
    Conn& c = it->second;
    if (c.overloaded) return false;
    // past its own cap or the global budget: the overload line instead, then the connection goes
    const size_t pending = c.out.size() + c.unsent;
    if (c.diversion) {
      // the diversion wakes its own reader; the I/O thread only if the connection is to close
      if (c.diversion->write(data)) return true;
      mark_overloaded(c);
    } else if (pending + data.size() > limits_.max_pending_bytes ||
               total_pending_ + data.size() > limits_.max_total_pending_bytes) {
      mark_overloaded(c);
    } else {
      c.out += data;
      total_pending_ += data.size();
    }
  }
  if (wakeups_held_.load()) {
    wake_deferred_.store(true);
    // released meanwhile: this send's wake-up may have been missed by release_wakeups()
    if (!wakeups_held_.load() && wake_deferred_.exchange(false)) wake();
  } else {
    wake();
  }
  return true;
}

void LineServer::release_wakeups() {
  wakeups_held_.store(false);
  if (wake_deferred_.exchange(false)) wake();
}

bool LineServer::divert(uint64_t conn, std::shared_ptr<Diversion> diversion) {
  std::lock_guard<std::mutex> lock(out_mutex_);
  auto it = conns_.find(conn);
  if (it == conns_.end() || it->second.overloaded) return false;
  it->second.diversion = std::move(diversion);
  return true;
}

void LineServer::close_overloaded(uint64_t conn) {
  {
    std::lock_guard<std::mutex> lock(out_mutex_);
    auto it = conns_.find(conn);
    if (it == conns_.end()) return;
    mark_overloaded(it->second);
  }
  wake();
}

void LineServer::close_when_sent(uint64_t conn) {
  {
    std::lock_guard<std::mutex> lock(out_mutex_);
    auto it = conns_.find(conn);
    if (it == conns_.end()) return;
    it->second.close_requested = true;
  }
  wake();
}

bool LineServer::finished(const Conn& c) {
  std::lock_guard<std::mutex> lock(out_mutex_);
  const bool all_sent = c.out.empty() && c.sent >= c.sending.size();
  if (c.overloaded) return all_sent || steady_now_s() - c.overloaded_at_s > kOverloadGrace_s;
  return c.close_requested && c.read_closed && all_sent;
}

size_t LineServer::pending_bytes(uint64_t conn) {
  std::lock_guard<std::mutex> lock(out_mutex_);
  auto it = conns_.find(conn);
  if (it == conns_.end()) return 0;
  const Conn& c = it->second;
  return c.out.size() + c.unsent + (c.diversion ? c.diversion->pending_bytes() : 0);
}

void LineServer::accept_all() {
  for (;;) {
    sockaddr_in peer{};
    socklen_t peer_len = sizeof(peer);
    const int fd = accept4(listen_fd_, reinterpret_cast<sockaddr*>(&peer), &peer_len, SOCK_NONBLOCK | SOCK_CLOEXEC);
    if (fd < 0) {
      if ((errno == EMFILE || errno == ENFILE) && spare_fd_ >= 0) {
        // out of descriptors: the waiting connection would keep the listener readable and this thread
        // spinning; give up the spare to accept it, close it at once, and take the spare back. accept
        // reports EMFILE before it looks at the queue, so an empty queue shows only here: stop then
        close(spare_fd_);
        const int doomed = accept(listen_fd_, nullptr, nullptr);
        if (doomed >= 0) close(doomed);
        spare_fd_ = open_spare_fd();
        if (doomed < 0) return;
        fd_exhausted_accepts_.fetch_add(1);
        continue;
      }
      return;
    }
    char ip[INET_ADDRSTRLEN] = {};
    inet_ntop(AF_INET, &peer.sin_addr, ip, sizeof(ip));
    (void)common::configure_accepted_tcp(fd);  // no Nagle delay; keepalive drops vanished peers
    {
      std::lock_guard<std::mutex> lock(out_mutex_);
      if (conns_.size() >= limits_.max_connections) {
        // over the connection limit: say why, then close (a best-effort write into a fresh socket)
        [[maybe_unused]] const ssize_t n =
            ::send(fd, limits_.overload_line.data(), limits_.overload_line.size(), MSG_NOSIGNAL);
        close(fd);
        continue;
      }
    }
    uint64_t id = 0;
    {
      std::lock_guard<std::mutex> lock(out_mutex_);
      id = next_id_++;
      conns_[id].fd = fd;
      conns_[id].peer = ip;
    }
    if (callbacks_.on_connect) callbacks_.on_connect(id);
  }
}

std::string LineServer::peer_address(uint64_t conn) const {
  std::lock_guard<std::mutex> lock(out_mutex_);
  auto it = conns_.find(conn);
  return it == conns_.end() ? std::string() : it->second.peer;
}

LineServer::ReadResult LineServer::read_conn(uint64_t id, Conn& c) {
  char buf[65536];
  for (;;) {
    const ssize_t n = recv(c.fd, buf, sizeof(buf), 0);
    if (n == 0) {
      // EOF: an unterminated last line is still a request
      if (!c.discarding && !c.in.empty() && callbacks_.on_line) {
        if (c.in.back() == '\r') c.in.pop_back();
        callbacks_.on_line(id, std::move(c.in));
      }
      c.in.clear();
      return ReadResult::kEof;
    }
    if (n < 0) {
      return errno == EAGAIN || errno == EWOULDBLOCK || errno == EINTR ? ReadResult::kOpen : ReadResult::kFailed;
    }
    size_t start = 0;
    for (size_t i = 0; i < static_cast<size_t>(n); ++i) {
      if (buf[i] != '\n') continue;
      // a complete line: deliver it, unless it is the tail of an over-long one
      if (!c.discarding) {
        c.in.append(buf + start, i - start);
        if (!c.in.empty() && c.in.back() == '\r') c.in.pop_back();
        if (c.in.size() > max_line_bytes_) {
          if (callbacks_.on_line_too_long) callbacks_.on_line_too_long(id);
        } else if (callbacks_.on_line) {
          callbacks_.on_line(id, std::move(c.in));
        }
      }
      c.in.clear();
      c.discarding = false;
      start = i + 1;
    }
    if (!c.discarding) c.in.append(buf + start, static_cast<size_t>(n) - start);
    if (!c.discarding && c.in.size() > max_line_bytes_) {
      // report once, then skip to the next newline
      if (callbacks_.on_line_too_long) callbacks_.on_line_too_long(id);
      c.in.clear();
      c.discarding = true;
    }
  }
}

bool LineServer::write_conn(Conn& c) {
  for (;;) {
    if (c.sent >= c.sending.size()) {
      // the next batch: swap buffers, so the emptied one takes the next messages without reallocating
      c.sending.clear();
      c.sent = 0;
      std::lock_guard<std::mutex> lock(out_mutex_);
      c.sending.swap(c.out);
      c.unsent = c.sending.size();
      if (c.sending.empty()) return true;
    }
    const ssize_t n = ::send(c.fd, c.sending.data() + c.sent, c.sending.size() - c.sent, MSG_NOSIGNAL);
    if (n < 0) return errno == EAGAIN || errno == EWOULDBLOCK || errno == EINTR;
    c.sent += static_cast<size_t>(n);
    std::lock_guard<std::mutex> lock(out_mutex_);
    c.unsent = c.sending.size() - c.sent;
    total_pending_ -= static_cast<size_t>(n);
  }
}

void LineServer::run() {
  std::vector<pollfd> fds;
  std::vector<uint64_t> ids;
  while (!stop_) {
    // poll set: wake-up pipe, listener, every connection (POLLOUT while output is pending)
    fds.clear();
    ids.clear();
    fds.push_back({wake_fds_[0], POLLIN, 0});
    fds.push_back({listen_fd_, POLLIN, 0});
    {
      std::lock_guard<std::mutex> lock(out_mutex_);
      for (auto& [id, c] : conns_) {
        // no POLLIN after EOF (it would stay readable) or once overloaded (its requests are not served)
        const bool pending = !c.out.empty() || c.sent < c.sending.size();
        const bool reading = !c.read_closed && !c.overloaded;
        fds.push_back({c.fd, static_cast<short>((reading ? POLLIN : 0) | (pending ? POLLOUT : 0)), 0});
        ids.push_back(id);
      }
    }
    if (poll(fds.data(), fds.size(), 200) < 0 && errno != EINTR) break;
    if (fds[0].revents & POLLIN) {
      char drain[256];
      while (read(wake_fds_[0], drain, sizeof(drain)) > 0) {
      }
      wake_pending_.store(false);  // before the queues are looked at below (see wake())
    }
    if (fds[1].revents & POLLIN) accept_all();

    std::vector<uint64_t> closed;
    for (size_t k = 0; k < ids.size(); ++k) {
      const short ev = fds[k + 2].revents;
      Conn* c = nullptr;
      {
        std::lock_guard<std::mutex> lock(out_mutex_);
        auto it = conns_.find(ids[k]);
        if (it == conns_.end()) continue;
        c = &it->second;  // stable: only this thread erases
      }
      bool ok = true;
      if (!c->read_closed && (ev & (POLLIN | POLLHUP | POLLERR))) {
        const ReadResult r = read_conn(ids[k], *c);
        ok = r != ReadResult::kFailed;
        if (r == ReadResult::kEof) {
          // the owner answers what it got, then calls close_when_sent
          c->read_closed = true;
          if (callbacks_.on_disconnect) callbacks_.on_disconnect(ids[k]);
        }
      }
      if (ok && (ev & (POLLHUP | POLLERR)) && c->read_closed) ok = false;  // nobody left to write to
      if (ok) ok = write_conn(*c);
      if (!ok) closed.push_back(ids[k]);
    }
    // flush output queued since the poll (replies to what was just read), then close what is done
    // (conns_ changes membership on this thread only: iterating it here needs no lock)
    for (auto& [id, c] : conns_) {
      if (!write_conn(c) || finished(c)) closed.push_back(id);
    }
    for (uint64_t id : closed) {
      int fd = -1;
      bool reported = false;
      {
        std::lock_guard<std::mutex> lock(out_mutex_);
        auto it = conns_.find(id);
        if (it == conns_.end()) continue;
        fd = it->second.fd;
        reported = it->second.read_closed;
        total_pending_ -= it->second.out.size() + it->second.unsent;
        conns_.erase(it);
      }
      close(fd);
      if (!reported && callbacks_.on_disconnect) callbacks_.on_disconnect(id);
    }
  }
}

}  // namespace uavsim::server::api
