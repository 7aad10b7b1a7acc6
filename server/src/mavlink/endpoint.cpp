#include "mavlink/endpoint.hpp"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <chrono>
#include <condition_variable>
#include <cstring>
#include <mutex>
#include <span>
#include <stdexcept>
#include <string>
#include <unordered_map>

#include "mavlink/tlog.hpp"
#include "mavlink/vehicle_link.hpp"
#include "net/event_loop.hpp"
#include "net/tcp_acceptor.hpp"
#include "uavsim/common/mavlink/parser.hpp"
#include "uavsim/common/tcp_socket.hpp"

namespace uavsim::server::mavlink {

namespace {

// what the I/O thread hands to the loop thread, per vehicle
struct InEvent {
  enum class Kind { kConnect, kFrame, kDisconnect };
  Kind kind = Kind::kFrame;
  std::uint64_t client = 0;
  std::shared_ptr<Outbox> outbox;  // kConnect only
  std::string peer;                // kConnect, kDisconnect: "tcp:ADDR:PORT", "udp:ADDR:PORT"
  Frame frame;                     // kFrame only (raw cleared: it pointed into the parser)
  std::vector<std::uint8_t> raw;   // kFrame with a telemetry log: the frame's bytes
};

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

// Shared by the server object, the I/O thread, the control observer and the posted tasks; the
// observer and tasks hold it weakly so they become no-ops once the server is gone.
struct MavlinkServer::Core {
  struct Vehicle {
    std::unique_ptr<VehicleLink> link;  // loop thread only
    StatCounters stats;
    SigningKeyCell signing;                      // set by the link, read by the I/O thread
    std::unique_ptr<net::TcpAcceptor> acceptor;  // null without TCP; lives as long as the Core
    std::uint16_t port = 0;
    std::vector<std::uint16_t> udp_ports;  // local port of each UDP link
    std::mutex inbox_mutex;
    std::vector<InEvent> inbox;    // guarded by inbox_mutex
    std::size_t inbox_frames = 0;  // guarded by inbox_mutex
    bool task_posted = false;      // guarded by inbox_mutex
    std::atomic<bool> link_down{false};
    mutable std::mutex seq_mutex;
    std::unordered_map<std::uint64_t, std::uint8_t>
        last_seq;  // client id -> last handled seq; seq_mutex
  };
  struct Client {  // I/O thread only
    int fd = -1;
    std::size_t vehicle = 0;
    std::uint64_t id = 0;
    Parser parser;
    ParserStats parser_seen;
    std::uint64_t signing_generation =
        0;  // of the vehicle's SigningKeyCell the parser is configured with
    std::shared_ptr<Outbox> outbox;
    std::string datagrams;  // a UDP link's frames being sent
    bool want_out = false;  // watched for EPOLLOUT: bytes are stuck in the socket
    std::string peer;  // "tcp:ADDR:PORT" / "udp:ADDR:PORT"; empty while a udpin link has no peer
    bool udp = false;  // a UDP link: one datagram per frame, never closed by its peer
  };

  sim::Simulation& sim;
  EndpointConfig config;
  std::unique_ptr<net::EventLoop> own_loop;        // without a shared loop
  net::EventLoop& loop;                            // the I/O thread
  net::FdReserve fd_reserve;                       // every vehicle's acceptor's, on the I/O thread
  std::vector<std::unique_ptr<Vehicle>> vehicles;  // after the loop: their acceptors go first
  net::Waker* waker = nullptr;  // flush_all(); set before the loop serves this endpoint
  std::atomic<bool> stop{false};
  std::atomic<std::uint64_t> wakeups{0};
  std::mutex
      seq_listener_mutex;  // the I/O thread runs from construction: set_seq_listener races it
  std::function<void()> seq_listener;
  std::unordered_map<int, std::unique_ptr<Client>> clients;  // by fd; I/O thread only
  std::uint64_t next_client_id = 1;                          // I/O thread only
  std::weak_ptr<Core> self;
  // flush_queued(): a request generation, and the last generation the I/O thread has flushed
  std::mutex flush_mutex;
  std::condition_variable flush_cv;
  std::uint64_t flush_requested = 0;  // guarded by flush_mutex
  std::uint64_t flush_done = 0;       // guarded by flush_mutex

  Core(sim::Simulation& s, const EndpointConfig& c, net::EventLoop* shared_loop)
      : sim(s),
        config(c),
        own_loop(shared_loop == nullptr ? std::make_unique<net::EventLoop>() : nullptr),
        loop(shared_loop == nullptr ? *own_loop : *shared_loop) {}
  ~Core() { shutdown(); }

  // startup: one listening socket per vehicle and the UDP links (throws on failure), then the I/O
  // thread serves them
  void open(std::shared_ptr<Core> shared) {
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

  void watch_client(int fd) {
    loop.watch(fd, EPOLLIN | EPOLLRDHUP,
               [this, fd](std::uint32_t events) { on_client_events(fd, events); });
  }

  // a UDP link: udpclient sockets are connected to their ground station and start streaming at
  // once; udpin sockets wait for a peer (read_client latches onto the first one)
  void open_udp(std::size_t vehicle, const UdpEndpoint& u) {
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
                               std::string(u.listen ? "listen on " : "send to ") + url + ": " +
                               err);
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

  // a UDP link has its peer: from now on it is a client of the vehicle like a TCP connection
  void latch_udp(Client& c, std::string peer) {
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

  // --- loop thread -> I/O thread ---
  void wake() {
    wakeups.fetch_add(1, std::memory_order_relaxed);
    waker->wake();  // one eventfd write until the I/O thread has served it
  }

  // a new flush generation, one wake-up, then wait until the I/O thread has flushed it
  bool flush_queued(double timeout_s) {
    std::uint64_t generation = 0;
    {
      std::lock_guard lock(flush_mutex);
      generation = ++flush_requested;
    }
    wake();
    using SteadyClock = std::chrono::steady_clock;
    const auto deadline = SteadyClock::now() + std::chrono::duration_cast<SteadyClock::duration>(
                                                   std::chrono::duration<double>(timeout_s));
    std::unique_lock lock(flush_mutex);
    return flush_cv.wait_until(lock, deadline, [&] {
      return flush_done >= generation || stop.load();
    }) && flush_done >= generation;
  }

  // I/O thread: the bytes queued before request `generation` are on the wire (or stuck in a full
  // socket)
  void publish_flushed(std::uint64_t generation) {
    {
      std::lock_guard lock(flush_mutex);
      if (generation <= flush_done) return;
      flush_done = generation;
    }
    flush_cv.notify_all();
  }

  // --- I/O thread -> loop thread ---
  void push_event(std::size_t vehicle, InEvent&& ev) {
    Vehicle& v = *vehicles[vehicle];
    bool post = false;
    {
      std::lock_guard lock(v.inbox_mutex);
      if (ev.kind == InEvent::Kind::kFrame) {
        if (v.inbox_frames >= config.inbox_frames) {
          StatCounters::add(v.stats.inbox_dropped);
          return;
        }
        ++v.inbox_frames;
      }
      v.inbox.push_back(std::move(ev));
      if (!v.task_posted) v.task_posted = post = true;
    }
    if (post) {
      std::weak_ptr<Core> weak = self;
      sim.post(vehicle, [weak, vehicle](fc::FlightController& fc) {
        if (auto core = weak.lock()) core->drain_inbox(vehicle, fc);
      });
    }
  }

  // a world reset drops every queued vehicle task, this endpoint's inbox drains among them: a
  // vehicle whose drain was posted would keep task_posted set and never be served again (no
  // heartbeat for a client that connected around the reset). Loop thread, after the tasks were
  // cleared.
  void after_reset() {
    for (std::size_t vehicle = 0; vehicle < vehicles.size(); ++vehicle) {
      Vehicle& v = *vehicles[vehicle];
      bool post = false;
      {
        std::lock_guard lock(v.inbox_mutex);
        post = !v.inbox.empty();
        v.task_posted = post;
      }
      if (!post) continue;
      std::weak_ptr<Core> weak = self;
      sim.post(vehicle, [weak, vehicle](fc::FlightController& fc) {
        if (auto core = weak.lock()) core->drain_inbox(vehicle, fc);
      });
    }
  }

  // runs on the loop thread as a vehicle task: handle everything queued for the vehicle
  void drain_inbox(std::size_t vehicle, fc::FlightController& fc) {
    Vehicle& v = *vehicles[vehicle];
    std::vector<InEvent> events;
    {
      std::lock_guard lock(v.inbox_mutex);
      events.swap(v.inbox);
      v.inbox_frames = 0;
      v.task_posted = false;
    }
    for (InEvent& e : events) {
      switch (e.kind) {
        case InEvent::Kind::kConnect:
          v.link->on_connect(e.client, std::move(e.outbox));
          if (config.on_client) config.on_client(vehicle, true, e.peer);
          break;
        case InEvent::Kind::kDisconnect:
          v.link->on_disconnect(e.client);
          if (config.on_client) config.on_client(vehicle, false, e.peer);
          break;
        case InEvent::Kind::kFrame:
          if (!e.raw.empty()) v.link->log_received(e.raw);
          v.link->on_frame(e.client, e.frame, fc);
          break;
      }
    }
    (void)v.link->take_queued();  // the replies go with this wake-up
    wake();
  }

  // the control observer: telemetry of every vehicle, then one wake-up for the I/O thread if any of
  // it queued a frame (most control steps send nothing: streams run at a few to 50 Hz, control at
  // 400 Hz, and an eventfd write per step was 6 % of the loop thread)
  void on_control_step() {
    bool any = false;
    for (auto& v : vehicles) {
      v->link->on_control_step();
      any = v->link->take_queued() || any;
    }
    if (any) wake();
  }

  // --- I/O thread ---
  void on_wake() {
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

  void on_client_events(int fd, std::uint32_t events) {
    auto it = clients.find(fd);
    if (it == clients.end()) return;
    Client& c = *it->second;
    bool alive = true;
    if (events & (EPOLLIN | EPOLLERR | EPOLLHUP | EPOLLRDHUP)) alive = read_client(c);
    if (alive && (events & EPOLLOUT)) alive = flush_client(c);
    if (!alive) close_client(fd);
  }

  // a TCP connection accepted on vehicle's port
  void add_client(std::size_t vehicle, int fd, const sockaddr_in& peer) {
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

  // false when the client is gone
  bool read_client(Client& c) {
    bool handled_any = false;
    const bool alive = read_client_bytes(c, handled_any);
    // a lockstep `done` may be waiting for one of these messages' seq (api::SeqWaiter)
    if (handled_any) {
      std::lock_guard lock(seq_listener_mutex);
      if (seq_listener) seq_listener();
    }
    return alive;
  }

  bool read_client_bytes(Client& c, bool& handled_any) {
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

  void account_parser(Client& c) {
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

  void flush_all() {
    std::vector<int> dead;
    for (auto& [fd, c] : clients) {
      if (!c->outbox->buffer().has_queued() && !c->want_out) continue;
      if (!flush_client(*c)) dead.push_back(fd);
    }
    for (int fd : dead) close_client(fd);
  }

  // writes what it can without blocking; false when the client is gone
  bool flush_client(Client& c) {
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

  // a UDP link sends one datagram per frame, as ArduPilot does; what the socket refuses is lost
  void flush_datagrams(Client& c) {
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

  void close_client(int fd) {
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

  // stops serving: no handler of this endpoint runs after it, every socket is closed (the shared
  // loop, if any, goes on for its other users). Idempotent.
  void shutdown() {
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
};

MavlinkServer::MavlinkServer(sim::Simulation& sim, const EndpointConfig& config,
                             net::EventLoop* io_loop)
    : core_(std::make_shared<Core>(sim, config, io_loop)) {
  core_->open(core_);
  // sim_vehicle.py --auto-sysid: vehicle i is system i + 1
  if (config.auto_sysid) {
    for (std::size_t i = 0; i < sim.vehicle_count(); ++i) {
      sim.post(i, [i](fc::FlightController& fc) {
        fc.set_param("SYSID_THISMAV", static_cast<double>(i + 1));
      });
    }
  }
}

MavlinkServer::~MavlinkServer() { core_->shutdown(); }

void MavlinkServer::schedule(sim::StepSchedule& steps) {
  std::weak_ptr<Core> weak = core_;
  steps.add(sim::Phase::kPostControl, "mavlink", [weak] {
    if (auto core = weak.lock()) core->on_control_step();
  });
  steps.add_reset("mavlink", [weak](uint64_t) {
    if (auto core = weak.lock()) core->after_reset();
  });
}

std::size_t MavlinkServer::vehicle_count() const { return core_->vehicles.size(); }
std::uint16_t MavlinkServer::port(std::size_t vehicle) const {
  return core_->vehicles.at(vehicle)->port;
}
std::uint16_t MavlinkServer::udp_port(std::size_t vehicle, std::size_t k) const {
  return core_->vehicles.at(vehicle)->udp_ports.at(k);
}
EndpointStats MavlinkServer::stats(std::size_t vehicle) const {
  const Core::Vehicle& v = *core_->vehicles.at(vehicle);
  EndpointStats s = v.stats.snapshot();
  if (v.acceptor) s.fd_exhausted_accepts = v.acceptor->exhausted_accepts();
  return s;
}
std::size_t MavlinkServer::client_count(std::size_t vehicle) const {
  return static_cast<std::size_t>(core_->vehicles.at(vehicle)->stats.clients_now.load());
}
const GimbalState& MavlinkServer::gimbal(std::size_t vehicle) const {
  return core_->vehicles.at(vehicle)->link->gimbal();
}
const EndpointConfig& MavlinkServer::config() const { return core_->config; }

bool MavlinkServer::set_link_down(std::size_t vehicle, bool down) {
  if (vehicle >= core_->vehicles.size()) return false;
  core_->vehicles[vehicle]->link_down.store(down);
  core_->wake();
  return true;
}

bool MavlinkServer::link_down(std::size_t vehicle) const {
  return vehicle < core_->vehicles.size() && core_->vehicles[vehicle]->link_down.load();
}

bool MavlinkServer::flush_queued(double timeout_s) { return core_->flush_queued(timeout_s); }

std::uint64_t MavlinkServer::io_wakeups() const {
  return core_->wakeups.load(std::memory_order_relaxed);
}

void MavlinkServer::set_seq_listener(std::function<void()> listener) {
  std::lock_guard lock(core_->seq_listener_mutex);
  core_->seq_listener = std::move(listener);
}

bool MavlinkServer::seq_processed(std::size_t vehicle, std::uint8_t seq) const {
  if (vehicle >= core_->vehicles.size()) return false;
  const Core::Vehicle& v = *core_->vehicles[vehicle];
  std::lock_guard lock(v.seq_mutex);
  for (const auto& [client, last] : v.last_seq) {
    if (static_cast<std::uint8_t>(last - seq) < 128) return true;
  }
  return false;
}

}  // namespace uavsim::server::mavlink
