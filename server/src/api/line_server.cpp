#include "api/line_server.hpp"

#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstdio>
#include <vector>

#include "uavsim/common/tcp_socket.hpp"

namespace uavsim::server::api {

namespace {

constexpr double kOverloadGrace_s =
    5.0;  // an overloaded peer that reads nothing is closed after this

double steady_now_s() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

}  // namespace

LineServer::LineServer(const std::string& bind_address, uint16_t port, Limits limits,
                       Callbacks callbacks, net::EventLoop* loop)
    : callbacks_(std::move(callbacks)),
      limits_(std::move(limits)),
      max_line_bytes_(limits_.max_line_bytes),
      own_loop_(loop == nullptr ? std::make_unique<net::EventLoop>() : nullptr),
      loop_(loop == nullptr ? *own_loop_ : *loop) {
  acceptor_ = std::make_unique<net::TcpAcceptor>(
      loop_, fd_reserve_, bind_address, port, 16, "sim API",
      [this](int fd, const sockaddr_in& peer) { on_accept(fd, net::ip_text(peer)); });
  port_ = acceptor_->port();
}

LineServer::~LineServer() { stop(); }

void LineServer::start() {
  loop_.call([this] {
    waker_.store(&loop_.make_waker([this] { serve_all(); }));
    // an overloaded peer that reads nothing is closed after its grace period, which no event marks
    tick_ = loop_.add_tick([this] {
      if (overloaded_conns_.load() > 0) serve_all();
    });
    acceptor_->start();
  });
  if (own_loop_) own_loop_->start();
}

void LineServer::stop() {
  if (stopped_.exchange(true)) return;
  if (own_loop_) own_loop_->stop();
  loop_.call([this] { teardown(); });
}

void LineServer::teardown() {
  acceptor_->stop();
  if (net::Waker* w = waker_.load()) {
    loop_.disable(*w);
    loop_.remove_tick(tick_);
  }
  std::lock_guard<std::mutex> lock(out_mutex_);
  for (auto& [id, c] : conns_) {
    drop_intake(c);
    loop_.unwatch(c.fd);
    close(c.fd);
    c.out.close();
  }
  conns_.clear();
  total_pending_ = 0;
}

void LineServer::mark_overloaded(Conn& c) {
  if (c.overloaded) return;
  c.overloaded = true;
  c.overloaded_at_s = steady_now_s();
  c.out.append_unbounded(limits_.overload_line);
  total_pending_ += limits_.overload_line.size();
  overloaded_conns_.fetch_add(1);
}

bool LineServer::send(uint64_t conn, const std::string& data, bool work_ahead) {
  {
    std::lock_guard<std::mutex> lock(out_mutex_);
    auto it = conns_.find(conn);
    if (it == conns_.end()) return false;
    Conn& c = it->second;
    if (c.overloaded) return false;
    // past its own cap or the global budget: the overload line instead, then the connection goes
    if (c.diversion) {
      // the diversion wakes its own reader; the I/O thread only if the connection is to close
      if (c.diversion->write(data, work_ahead)) return true;
      mark_overloaded(c);
    } else if (total_pending_ + data.size() > limits_.max_total_pending_bytes ||
               c.out.append(data) != net::WriteBuffer::Append::kQueued) {
      mark_overloaded(c);
    } else {
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

bool LineServer::add_intake(uint64_t conn, std::shared_ptr<Intake> intake) {
  bool added = false;
  loop_.call([&] {
    // membership changes on this thread only: no lock to look
    auto it = conns_.find(conn);
    if (it == conns_.end() || it->second.read_closed || it->second.intake) return;
    it->second.intake = std::move(intake);
    loop_.watch(it->second.intake->fd(), EPOLLIN, [this, conn](std::uint32_t) { on_intake(conn); });
    added = true;
  });
  return added;
}

void LineServer::on_intake(uint64_t id) {
  auto it = conns_.find(id);
  if (it == conns_.end() || !it->second.intake) return;
  Conn& c = it->second;
  {
    // an overloaded connection's requests are not served (as its socket is not read)
    std::lock_guard<std::mutex> lock(out_mutex_);
    if (c.overloaded) return drop_intake(c);
  }
  const Intake::Sink sink{[this, id](std::string line) {
                            if (line.size() > max_line_bytes_) {
                              if (callbacks_.on_line_too_long) callbacks_.on_line_too_long(id);
                            } else if (callbacks_.on_line) {
                              callbacks_.on_line(id, std::move(line));
                            }
                          },
                          [this, id](std::uint16_t type, std::span<const std::uint8_t> payload) {
                            if (callbacks_.on_record) callbacks_.on_record(id, type, payload);
                          }};
  std::string why;
  const bool ok = c.intake->read(sink, &why);
  if (callbacks_.on_read_end) callbacks_.on_read_end(id);
  if (ok) return;
  std::fprintf(stderr, "sim API: connection %llu dropped: %s\n",
               static_cast<unsigned long long>(id), why.c_str());
  drop_intake(c);
  close_overloaded(id);
}

void LineServer::drop_intake(Conn& c) {
  if (!c.intake) return;
  loop_.unwatch(c.intake->fd());
  c.intake.reset();
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
  const bool all_sent = c.out.unwritten() == 0;
  if (c.overloaded) return all_sent || steady_now_s() - c.overloaded_at_s > kOverloadGrace_s;
  return c.close_requested && c.read_closed && all_sent;
}

size_t LineServer::pending_bytes(uint64_t conn) {
  std::lock_guard<std::mutex> lock(out_mutex_);
  auto it = conns_.find(conn);
  if (it == conns_.end()) return 0;
  const Conn& c = it->second;
  return c.out.unwritten() + (c.diversion ? c.diversion->pending_bytes() : 0);
}

void LineServer::on_accept(int fd, const std::string& peer) {
  (void)common::configure_accepted_tcp(fd);  // no Nagle delay; keepalive drops vanished peers
  uint64_t id = 0;
  {
    std::lock_guard<std::mutex> lock(out_mutex_);
    if (conns_.size() >= limits_.max_connections) {
      // over the connection limit: say why, then close (a best-effort write into a fresh socket)
      [[maybe_unused]] const ssize_t n =
          ::send(fd, limits_.overload_line.data(), limits_.overload_line.size(), MSG_NOSIGNAL);
      close(fd);
      return;
    }
    id = next_id_++;
    Conn& c = conns_.try_emplace(id, fd, limits_.max_pending_bytes).first->second;
    c.peer = peer;
    c.interest = EPOLLIN;
  }
  loop_.watch(fd, EPOLLIN, [this, id](std::uint32_t events) { on_events(id, events); });
  if (callbacks_.on_connect) callbacks_.on_connect(id);
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
      return errno == EAGAIN || errno == EWOULDBLOCK || errno == EINTR ? ReadResult::kOpen
                                                                       : ReadResult::kFailed;
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
  size_t written = 0;
  const net::WriteBuffer::Write w = c.out.write_to(c.fd, &written);
  if (written > 0) {
    std::lock_guard<std::mutex> lock(out_mutex_);
    total_pending_ -= written;
  }
  return w != net::WriteBuffer::Write::kFailed;
}

void LineServer::watch_for(Conn& c) {
  bool reading = false;
  {
    std::lock_guard<std::mutex> lock(out_mutex_);
    // no EPOLLIN after EOF (it would stay readable) or once overloaded (its requests are not
    // served)
    reading = !c.read_closed && !c.overloaded;
  }
  const std::uint32_t want = (reading ? EPOLLIN : 0u) | (c.out.unwritten() > 0 ? EPOLLOUT : 0u);
  if (want == c.interest) return;
  c.interest = want;
  loop_.change(c.fd, want);
}

void LineServer::on_events(uint64_t id, std::uint32_t events) {
  Conn* c = nullptr;
  {
    std::lock_guard<std::mutex> lock(out_mutex_);
    auto it = conns_.find(id);
    if (it == conns_.end()) return;
    c = &it->second;  // stable: only this thread erases
  }
  bool ok = true;
  if (!c->read_closed && (events & (EPOLLIN | EPOLLHUP | EPOLLERR))) {
    const ReadResult r = read_conn(id, *c);
    if (callbacks_.on_read_end) callbacks_.on_read_end(id);
    ok = r != ReadResult::kFailed;
    if (r == ReadResult::kEof) {
      // the owner answers what it got, then calls close_when_sent
      c->read_closed = true;
      drop_intake(*c);  // nothing is served after the disconnect
      if (callbacks_.on_disconnect) callbacks_.on_disconnect(id);
    }
  }
  if (ok && (events & (EPOLLHUP | EPOLLERR)) && c->read_closed)
    ok = false;  // nobody left to write to
  // the replies to what was just read go out now, not a loop pass later
  if (ok) ok = write_conn(*c);
  if (!ok || finished(*c)) return close_conn(id);
  watch_for(*c);
}

void LineServer::serve_all() {
  // conns_ changes membership on this thread only: iterating it here needs no lock
  std::vector<uint64_t> closed;
  for (auto& [id, c] : conns_) {
    if (!write_conn(c) || finished(c)) {
      closed.push_back(id);
    } else {
      watch_for(c);
    }
  }
  for (uint64_t id : closed) close_conn(id);
}

void LineServer::close_conn(uint64_t id) {
  int fd = -1;
  bool reported = false;
  {
    std::lock_guard<std::mutex> lock(out_mutex_);
    auto it = conns_.find(id);
    if (it == conns_.end()) return;
    fd = it->second.fd;
    reported = it->second.read_closed;
    drop_intake(it->second);
    total_pending_ -= it->second.out.unwritten();
    if (it->second.overloaded) overloaded_conns_.fetch_sub(1);
    conns_.erase(it);
  }
  loop_.unwatch(fd);
  close(fd);
  if (!reported && callbacks_.on_disconnect) callbacks_.on_disconnect(id);
}

}  // namespace uavsim::server::api
