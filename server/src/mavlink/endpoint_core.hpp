// The MAVLink endpoints' shared state (endpoint.hpp's MavlinkServer::Core): the loop thread's side
// (the inbox hand-off, telemetry wake-ups, flushes) is in endpoint.cpp, the I/O thread's (sockets,
// parsing, signing checks, writes) in endpoint_io.cpp. Private to those two files.
#pragma once

#include <netinet/in.h>

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <unordered_map>
#include <vector>

#include "mavlink/endpoint.hpp"
#include "mavlink/outbox.hpp"
#include "mavlink/vehicle_link.hpp"
#include "net/event_loop.hpp"
#include "net/tcp_acceptor.hpp"
#include "uavsim/common/mavlink/parser.hpp"

namespace uavsim::server::mavlink {

struct MavlinkServer::Core {
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
    // client id -> last handled seq; guarded by seq_mutex
    std::unordered_map<std::uint64_t, std::uint8_t> last_seq;
  };
  struct Client {  // I/O thread only
    int fd = -1;
    std::size_t vehicle = 0;
    std::uint64_t id = 0;
    Parser parser;
    ParserStats parser_seen;
    // of the vehicle's SigningKeyCell the parser is configured with
    std::uint64_t signing_generation = 0;
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
  // the I/O thread runs from construction: set_seq_listener races it
  std::mutex seq_listener_mutex;
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

  // --- the loop thread's side (endpoint.cpp) ---
  // --- loop thread -> I/O thread ---
  void wake();

  // a new flush generation, one wake-up, then wait until the I/O thread has flushed it
  bool flush_queued(double timeout_s);

  // I/O thread: the bytes queued before request `generation` are on the wire (or stuck in a full
  // socket)
  void publish_flushed(std::uint64_t generation);

  // --- I/O thread -> loop thread ---
  void push_event(std::size_t vehicle, InEvent&& ev);

  // a world reset drops every queued vehicle task, this endpoint's inbox drains among them: a
  // vehicle whose drain was posted would keep task_posted set and never be served again (no
  // heartbeat for a client that connected around the reset). Loop thread, after the tasks were
  // cleared.
  void after_reset();

  // runs on the loop thread as a vehicle task: handle everything queued for the vehicle
  void drain_inbox(std::size_t vehicle, fc::FlightController& fc);

  // the control observer: telemetry of every vehicle, then one wake-up for the I/O thread if any of
  // it queued a frame (most control steps send nothing: streams run at a few to 50 Hz, control at
  // 400 Hz, and an eventfd write per step was 6 % of the loop thread)
  void on_control_step();

  // --- startup and the I/O thread (endpoint_io.cpp) ---
  // startup: one listening socket per vehicle and the UDP links (throws on failure), then the I/O
  // thread serves them
  void open(std::shared_ptr<Core> shared);

  void watch_client(int fd);

  // a UDP link: udpclient sockets are connected to their ground station and start streaming at
  // once; udpin sockets wait for a peer (read_client latches onto the first one)
  void open_udp(std::size_t vehicle, const UdpEndpoint& u);

  // a UDP link has its peer: from now on it is a client of the vehicle like a TCP connection
  void latch_udp(Client& c, std::string peer);

  void on_wake();

  void on_client_events(int fd, std::uint32_t events);

  // a TCP connection accepted on vehicle's port
  void add_client(std::size_t vehicle, int fd, const sockaddr_in& peer);

  // false when the client is gone
  bool read_client(Client& c);

  bool read_client_bytes(Client& c, bool& handled_any);

  void account_parser(Client& c);

  void flush_all();

  // writes what it can without blocking; false when the client is gone
  bool flush_client(Client& c);

  // a UDP link sends one datagram per frame, as ArduPilot does; what the socket refuses is lost
  void flush_datagrams(Client& c);

  void close_client(int fd);

  // stops serving: no handler of this endpoint runs after it, every socket is closed (the shared
  // loop, if any, goes on for its other users). Idempotent.
  void shutdown();
};

}  // namespace uavsim::server::mavlink
