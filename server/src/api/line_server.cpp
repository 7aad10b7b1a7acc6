#include "api/line_server.hpp"

#include <arpa/inet.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <stdexcept>
#include <vector>

namespace uavsim::server::api {

namespace {

constexpr size_t kMaxPendingOutput = 256u << 20;  // a client that reads nothing is dropped past this

void set_nonblocking(int fd) { fcntl(fd, F_SETFL, fcntl(fd, F_GETFL, 0) | O_NONBLOCK); }

}  // namespace

LineServer::LineServer(const std::string& bind_address, uint16_t port, size_t max_line_bytes,
                       Callbacks callbacks)
    : callbacks_(std::move(callbacks)), max_line_bytes_(max_line_bytes) {
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
}

LineServer::~LineServer() {
  stop();
  for (auto& [id, c] : conns_) close(c.fd);
  if (listen_fd_ >= 0) close(listen_fd_);
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
  const char b = 1;
  [[maybe_unused]] ssize_t n = write(wake_fds_[1], &b, 1);  // full pipe: a wake-up is pending anyway
}

bool LineServer::send(uint64_t conn, const std::string& data) {
  {
    std::lock_guard<std::mutex> lock(out_mutex_);
    auto it = conns_.find(conn);
    if (it == conns_.end()) return false;
    it->second.out += data;
  }
  wake();
  return true;
}

size_t LineServer::pending_bytes(uint64_t conn) {
  std::lock_guard<std::mutex> lock(out_mutex_);
  auto it = conns_.find(conn);
  return it == conns_.end() ? 0 : it->second.out.size() + it->second.unsent;
}

void LineServer::accept_all() {
  for (;;) {
    const int fd = accept(listen_fd_, nullptr, nullptr);
    if (fd < 0) return;
    set_nonblocking(fd);
    const int one = 1;
    setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof(one));
    uint64_t id = 0;
    {
      std::lock_guard<std::mutex> lock(out_mutex_);
      id = next_id_++;
      conns_[id].fd = fd;
    }
    if (callbacks_.on_connect) callbacks_.on_connect(id);
  }
}

bool LineServer::read_conn(uint64_t id, Conn& c) {
  char buf[65536];
  for (;;) {
    const ssize_t n = recv(c.fd, buf, sizeof(buf), 0);
    if (n == 0) return false;
    if (n < 0) return errno == EAGAIN || errno == EWOULDBLOCK || errno == EINTR;
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
        const bool pending = !c.out.empty() || c.sent < c.sending.size();
        fds.push_back({c.fd, static_cast<short>(POLLIN | (pending ? POLLOUT : 0)), 0});
        ids.push_back(id);
      }
    }
    if (poll(fds.data(), fds.size(), 200) < 0 && errno != EINTR) break;
    if (fds[0].revents & POLLIN) {
      char drain[256];
      while (read(wake_fds_[0], drain, sizeof(drain)) > 0) {
      }
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
      if (ev & (POLLIN | POLLHUP | POLLERR)) ok = read_conn(ids[k], *c);
      if (ok) ok = write_conn(*c) && pending_bytes(ids[k]) < kMaxPendingOutput;
      if (!ok) closed.push_back(ids[k]);
    }
    // flush output queued since the poll (replies to what was just read)
    // (conns_ changes membership on this thread only: iterating it here needs no lock)
    for (auto& [id, c] : conns_) {
      if (!write_conn(c)) closed.push_back(id);
    }
    for (uint64_t id : closed) {
      int fd = -1;
      {
        std::lock_guard<std::mutex> lock(out_mutex_);
        auto it = conns_.find(id);
        if (it == conns_.end()) continue;
        fd = it->second.fd;
        conns_.erase(it);
      }
      close(fd);
      if (callbacks_.on_disconnect) callbacks_.on_disconnect(id);
    }
  }
}

}  // namespace uavsim::server::api
