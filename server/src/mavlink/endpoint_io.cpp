// The I/O thread's side of the MAVLink endpoints: sockets on the server's event loop, frame parsing
// and the signing check per client, writes of each client's outbox (endpoint_core.hpp).
#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <span>
#include <stdexcept>
#include <string>

#include "mavlink/endpoint_core.hpp"
#include "uavsim/common/tcp_socket.hpp"

namespace uavsim::server::mavlink {

namespace {

constexpr std::size_t kReadChunk = 64 * 1024;
constexpr std::size_t kMaxReadPerWake = 256 * 1024;  // fairness between clients

using net::address_text;

sockaddr_in ipv4_address(const std::string& host, int port, const std::string& what) {
  sockaddr_in sa{};
  if (!net::ipv4_address(host, port, &sa)) {
    throw std::runtime_error("mavlink endpoint: " + what + ": not an IPv4 address: '" + host + "'");
  }
  return sa;
}

}  // namespace

void MavlinkServer::Core::open(std::shared_ptr<Core> shared) {
  self = shared;
  for (std::size_t i = 0; i < sim.vehicle_count(); ++i) {
    auto v = std::make_unique<Vehicle>();
    v->link = std::make_unique<VehicleLink>(sim, i, config, v->stats, v->signing);
    if (config.base_port >= 0) {
      const int port =
          config.base_port == 0 ? 0 : config.base_port + config.port_stride * static_cast<int>(i);
      // "--bind" in the address error: the option a user would fix
      if (sockaddr_in sa{}; !net::ipv4_address(config.bind_address, port, &sa)) {
        throw std::runtime_error("mavlink endpoint: --bind: not an IPv4 address: '" +
                                 config.bind_address + "'");
      }
      v->acceptor = std::make_unique<net::TcpAcceptor>(
          loop, fd_reserve, config.bind_address, port, 64, "mavlink endpoint",
          [this, i](int fd, const sockaddr_in& peer) { add_client(i, fd, peer); });
      v->port = v->acceptor->port();
    }
    vehicles.push_back(std::move(v));
    if (i < config.udp.size()) {
      for (const UdpEndpoint& u : config.udp[i]) open_udp(i, u);
    }
  }
  loop.call([this] {
    waker = &loop.make_waker([this] { on_wake(); });
    for (auto& [fd, c] : clients) watch_client(fd);
    for (auto& v : vehicles) {
      if (v->acceptor) v->acceptor->start();
    }
  });
  if (own_loop) own_loop->start();
}

void MavlinkServer::Core::watch_client(int fd) {
  loop.watch(fd, EPOLLIN | EPOLLRDHUP,
             [this, fd](std::uint32_t events) { on_client_events(fd, events); });
}

void MavlinkServer::Core::open_udp(std::size_t vehicle, const UdpEndpoint& u) {
  const std::string url =
      std::string(u.listen ? "udpin:" : "udp:") + u.host + ":" + std::to_string(u.port);
  sockaddr_in sa = ipv4_address(u.host, u.port, url);
  const int fd = socket(AF_INET, SOCK_DGRAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
  if (fd < 0) throw std::runtime_error("mavlink endpoint: socket() failed for " + url);
  const int rc = u.listen ? bind(fd, reinterpret_cast<sockaddr*>(&sa), sizeof(sa))
                          : connect(fd, reinterpret_cast<sockaddr*>(&sa), sizeof(sa));
  if (rc != 0) {
    const std::string err = std::strerror(errno);
    close(fd);
    throw std::runtime_error("mavlink endpoint: cannot " +
                             std::string(u.listen ? "listen on " : "send to ") + url + ": " + err);
  }
  sockaddr_in local{};
  socklen_t len = sizeof(local);
  getsockname(fd, reinterpret_cast<sockaddr*>(&local), &len);
  vehicles[vehicle]->udp_ports.push_back(ntohs(local.sin_port));
  auto c = std::make_unique<Client>();
  c->fd = fd;
  c->vehicle = vehicle;
  c->id = next_client_id++;
  c->udp = true;
  c->outbox = std::make_shared<Outbox>(config.client_buffer_bytes);
  Client& client = *c;  // watched once the loop serves this endpoint (open())
  clients[fd] = std::move(c);
  if (!u.listen) latch_udp(client, "udp:" + u.host + ":" + std::to_string(u.port));
}

void MavlinkServer::Core::latch_udp(Client& c, std::string peer) {
  Vehicle& v = *vehicles[c.vehicle];
  c.peer = std::move(peer);
  StatCounters::add(v.stats.clients_accepted);
  StatCounters::add(v.stats.clients_now);
  InEvent ev;
  ev.kind = InEvent::Kind::kConnect;
  ev.client = c.id;
  ev.outbox = c.outbox;
  ev.peer = c.peer;
  push_event(c.vehicle, std::move(ev));
}

void MavlinkServer::Core::on_wake() {
  if (stop.load()) return;
  // every flush request made before this wake-up is covered by the flush that follows
  std::uint64_t generation = 0;
  {
    std::lock_guard lock(flush_mutex);
    generation = flush_requested;
  }
  flush_all();
  publish_flushed(generation);
}

void MavlinkServer::Core::on_client_events(int fd, std::uint32_t events) {
  auto it = clients.find(fd);
  if (it == clients.end()) return;
  Client& c = *it->second;
  bool alive = true;
  if (events & (EPOLLIN | EPOLLERR | EPOLLHUP | EPOLLRDHUP)) alive = read_client(c);
  if (alive && (events & EPOLLOUT)) alive = flush_client(c);
  if (!alive) close_client(fd);
}

void MavlinkServer::Core::add_client(std::size_t vehicle, int fd, const sockaddr_in& peer) {
  Vehicle& v = *vehicles[vehicle];
  (void)common::configure_accepted_tcp(fd);  // no Nagle delay; keepalive drops vanished peers
  auto c = std::make_unique<Client>();
  c->fd = fd;
  c->vehicle = vehicle;
  c->id = next_client_id++;
  c->outbox = std::make_shared<Outbox>(config.client_buffer_bytes);
  c->peer = "tcp:" + address_text(peer);
  watch_client(fd);
  StatCounters::add(v.stats.clients_accepted);
  StatCounters::add(v.stats.clients_now);
  InEvent ev;
  ev.kind = InEvent::Kind::kConnect;
  ev.client = c->id;
  ev.outbox = c->outbox;
  ev.peer = c->peer;
  clients[fd] = std::move(c);
  push_event(vehicle, std::move(ev));
}

bool MavlinkServer::Core::read_client(Client& c) {
  bool handled_any = false;
  const bool alive = read_client_bytes(c, handled_any);
  // a lockstep `done` may be waiting for one of these messages' seq (api::SeqWaiter)
  if (handled_any) {
    std::lock_guard lock(seq_listener_mutex);
    if (seq_listener) seq_listener();
  }
  return alive;
}

bool MavlinkServer::Core::read_client_bytes(Client& c, bool& handled_any) {
  Vehicle& v = *vehicles[c.vehicle];
  std::uint8_t buf[kReadChunk];
  std::size_t total = 0;
  while (total < kMaxReadPerWake) {
    sockaddr_in from{};
    socklen_t from_len = sizeof(from);
    const ssize_t n =
        recvfrom(c.fd, buf, sizeof(buf), 0, reinterpret_cast<sockaddr*>(&from), &from_len);
    if (c.udp) {
      // datagrams: an empty one is not an end; ICMP port-unreachable (no ground station listening
      // yet) and other errors leave the link as it is
      if (n < 0) return true;
      if (c.peer.empty()) {
        // a udpin link answers its first peer: connect to it, so that only it is heard from now
        // on
        if (connect(c.fd, reinterpret_cast<sockaddr*>(&from), from_len) != 0) continue;
        latch_udp(c, "udp:" + address_text(from));
      }
    } else {
      if (n == 0) return false;
      if (n < 0) return errno == EAGAIN || errno == EWOULDBLOCK || errno == EINTR;
    }
    total += static_cast<std::size_t>(n);
    if (v.link_down.load(std::memory_order_relaxed))
      continue;  // a dropped link: the bytes are lost
    StatCounters::add(v.stats.bytes_received, static_cast<std::uint64_t>(n));
    // a new signing key (SETUP_SIGNING handled since the last read): the parser checks signatures
    // and replays; which unsigned frames pass is decided below, per message
    if (const std::uint64_t generation = v.signing.generation();
        generation != c.signing_generation) {
      c.signing_generation = generation;
      ParserConfig pc;
      pc.signing_key = v.signing.get();
      pc.accept_unsigned = true;
      c.parser.configure(pc);
    }
    const bool signing = v.signing.get().has_value();
    c.parser.feed({buf, static_cast<std::size_t>(n)}, [&](const Frame& f) {
      if (signing && !f.signature && !accepted_unsigned(f.msgid)) {
        StatCounters::add(v.stats.unsigned_rejected);
        return;
      }
      InEvent ev;
      ev.kind = InEvent::Kind::kFrame;
      ev.client = c.id;
      ev.frame = f;
      ev.frame.raw = {};
      if (!config.tlog_dir.empty()) ev.raw.assign(f.raw.begin(), f.raw.end());
      const std::uint8_t seq = f.seq;
      push_event(c.vehicle, std::move(ev));
      std::lock_guard lock(v.seq_mutex);
      v.last_seq[c.id] = seq;
      handled_any = true;
    });
    account_parser(c);
  }
  return true;
}

void MavlinkServer::Core::account_parser(Client& c) {
  StatCounters& s = vehicles[c.vehicle]->stats;
  const ParserStats& now = c.parser.stats();
  ParserStats& was = c.parser_seen;
  StatCounters::add(s.frames_received, now.frames - was.frames);
  StatCounters::add(s.bytes_discarded, now.bytes_dropped - was.bytes_dropped);
  StatCounters::add(s.bad_crc, now.bad_crc - was.bad_crc);
  StatCounters::add(s.unknown_msgid, now.unknown_msgid - was.unknown_msgid);
  StatCounters::add(s.bad_length, now.bad_length - was.bad_length);
  StatCounters::add(s.bad_incompat_flags, now.bad_incompat_flags - was.bad_incompat_flags);
  StatCounters::add(s.bad_signature, now.bad_signature - was.bad_signature);
  StatCounters::add(s.replayed, now.replayed - was.replayed);
  was = now;
}

void MavlinkServer::Core::flush_all() {
  std::vector<int> dead;
  for (auto& [fd, c] : clients) {
    if (!c->outbox->buffer().has_queued() && !c->want_out) continue;
    if (!flush_client(*c)) dead.push_back(fd);
  }
  for (int fd : dead) close_client(fd);
}

bool MavlinkServer::Core::flush_client(Client& c) {
  Vehicle& v = *vehicles[c.vehicle];
  net::WriteBuffer& out = c.outbox->buffer();
  if (v.link_down.load(std::memory_order_relaxed)) {
    // a dropped link: what the vehicle sends meanwhile is lost
    out.take_queued(c.datagrams);
    c.datagrams.clear();
    return true;
  }
  if (c.udp) {
    flush_datagrams(c);
    return true;
  }
  std::size_t written = 0;
  const net::WriteBuffer::Write result = out.write_to(c.fd, &written);
  StatCounters::add(v.stats.bytes_sent, written);
  if (result == net::WriteBuffer::Write::kFailed) return false;
  // ask for EPOLLOUT only while bytes are stuck in the socket
  const bool stuck = result == net::WriteBuffer::Write::kBlocked;
  if (stuck != c.want_out) {
    loop.change(c.fd, EPOLLIN | EPOLLRDHUP | (stuck ? EPOLLOUT : 0u));
    c.want_out = stuck;
  }
  return true;
}

void MavlinkServer::Core::flush_datagrams(Client& c) {
  Vehicle& v = *vehicles[c.vehicle];
  while (c.outbox->buffer().has_queued()) {
    c.outbox->buffer().take_queued(c.datagrams);
    std::span<const std::uint8_t> rest(reinterpret_cast<const std::uint8_t*>(c.datagrams.data()),
                                       c.datagrams.size());
    while (!rest.empty()) {
      const std::size_t len = std::min(frame_length(rest), rest.size());
      if (len == 0) break;  // not a frame start: the outbox only holds whole frames, so never
      if (!c.peer.empty()) {
        const ssize_t n = send(c.fd, rest.data(), len, MSG_NOSIGNAL | MSG_DONTWAIT);
        if (n > 0) StatCounters::add(v.stats.bytes_sent, static_cast<std::uint64_t>(n));
      }
      rest = rest.subspan(len);
    }
  }
  c.datagrams.clear();
}

void MavlinkServer::Core::close_client(int fd) {
  auto it = clients.find(fd);
  if (it == clients.end()) return;
  Client& c = *it->second;
  loop.unwatch(fd);
  close(fd);
  c.outbox->close();
  Vehicle& v = *vehicles[c.vehicle];
  StatCounters::add(v.stats.clients_closed);
  v.stats.clients_now.fetch_sub(1, std::memory_order_relaxed);
  InEvent ev;
  ev.kind = InEvent::Kind::kDisconnect;
  ev.client = c.id;
  ev.peer = c.peer;
  const std::size_t vehicle = c.vehicle;
  {
    std::lock_guard lock(v.seq_mutex);
    v.last_seq.erase(c.id);
  }
  clients.erase(it);
  push_event(vehicle, std::move(ev));
}

void MavlinkServer::Core::shutdown() {
  if (stop.exchange(true)) return;
  flush_cv.notify_all();
  if (own_loop) own_loop->stop();
  loop.call([this] {
    if (waker != nullptr) loop.disable(*waker);
    for (auto& [fd, c] : clients) {
      loop.unwatch(fd);
      c->outbox->close();
      close(fd);
    }
    clients.clear();
    for (auto& v : vehicles) {
      if (v->acceptor) v->acceptor->stop();
    }
  });
}

}  // namespace uavsim::server::mavlink
