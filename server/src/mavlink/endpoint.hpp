// The per-vehicle MAVLink endpoints: ArduCopter SITL's behaviour on the wire.
//
// Vehicle i listens on TCP base_port + 10 i (ArduPilot SITL's -I convention), several clients at
// once, and may have UDP links beside (ArduPilot's udpclient/udpin: a ground station on a UDP
// port). Threads:
//   * one network I/O thread for every endpoint, the server's event loop (net/event_loop.hpp; its
//   own, or
//     one shared with the sim API): accepts, reads and parses frames, writes queued bytes. It never
//     touches a flight controller.
//   * the simulation loop thread: incoming frames are queued per vehicle and handled in a task
//   posted with
//     Simulation::post() (so commands take effect at control boundaries in vehicle order); the
//     replies and all telemetry are encoded there (telemetry from a control observer, scheduled in
//     sim time) into per-client bounded buffers (outbox.hpp) that the I/O thread drains.
// A slow or dead client costs only its own frames (dropped and counted); bad input is skipped and
// counted.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "mavlink/gimbal_state.hpp"
#include "sim/simulation.hpp"
#include "uavsim/common/geodesy.hpp"

namespace uavsim::server::net {
class EventLoop;
}

namespace uavsim::server::mavlink {

// The geodetic origin and conversions are the common ones (uavsim/common/geodesy.hpp).
using ::uavsim::common::Geodetic;
using ::uavsim::common::geodetic_from_ned;
using ::uavsim::common::GeodeticOrigin;
using ::uavsim::common::ned_from_geodetic;

// One UDP link of a vehicle (ArduPilot's udpclient / udpin serial protocols, mavlink-router's
// endpoints).
struct UdpEndpoint {
  bool listen =
      false;  // false: send to host:port from an ephemeral port and answer what comes back from
              // there; true: listen on host:port and answer the first peer that sends
  std::string host;  // IPv4 address
  int port = 0;
};

struct EndpointConfig {
  std::string bind_address =
      "127.0.0.1";       // loopback by default; a non-loopback address must be explicit
  int base_port = 5760;  // vehicle i: base_port + port_stride * i; 0: ephemeral ports;
                         // -1: no TCP listeners (UDP links only)
  int port_stride = 10;
  GeodeticOrigin origin;   // geodetic position of the world origin
  bool auto_sysid = true;  // vehicle i gets SYSID_THISMAV = i + 1 (sim_vehicle.py --auto-sysid)
  std::size_t client_buffer_bytes =
      512 * 1024;                   // per-client outgoing limit; frames beyond are dropped
  std::size_t inbox_frames = 4096;  // per-vehicle incoming frames awaiting the loop thread
  // MAVLink 2 signing from the start (--mavlink-key) for every vehicle; a client's SETUP_SIGNING
  // replaces it (an all-zero key turns signing off). See VehicleLink for the rules.
  std::optional<std::array<std::uint8_t, 32>> signing_key;
  // udp[i]: vehicle i's UDP links beside its TCP endpoint (a vehicle past the end has none). A udp
  // link is one more client of the vehicle (its own streams, sequence numbers and MAVLink version).
  std::vector<std::vector<UdpEndpoint>> udp;
  // Non-empty: DIR/VEHICLE_NAME.tlog per vehicle, every frame sent to and received from its clients
  // (tlog.hpp), stamped with sim time. The directory must exist.
  std::string tlog_dir;
  // Optional observers, called on the loop thread: a client connected (true) or left (false), with
  // its peer as "tcp:ADDR:PORT" or "udp:ADDR:PORT"; a flight-controller status text (MAV_SEVERITY,
  // text).
  std::function<void(std::size_t vehicle, bool connected, const std::string& peer)> on_client;
  std::function<void(std::size_t vehicle, int severity, const std::string& text)> on_status_text;
  // Optional, called on the loop thread: what a vehicle's simulated gimbal device measures now (its
  // stabilisation loop's lag included), for GIMBAL_DEVICE_ATTITUDE_STATUS and MOUNT_ORIENTATION.
  // Null, or nullopt for a vehicle: the commanded pointing is reported, as by a gimbal that follows
  // at once.
  std::function<std::optional<GimbalDeviceAttitude>(std::size_t vehicle)> gimbal_attitude;
};

// Counters of one vehicle's endpoint since start (a snapshot).
struct EndpointStats {
  std::uint64_t clients_accepted = 0;
  std::uint64_t clients_closed = 0;
  std::uint64_t bytes_received = 0;
  std::uint64_t bytes_sent = 0;
  std::uint64_t frames_received = 0;  // checksum-valid frames parsed
  std::uint64_t bytes_discarded =
      0;                      // bytes that were not part of a valid frame (garbage, bad frames)
  std::uint64_t bad_crc = 0;  // includes truncated frames
  std::uint64_t unknown_msgid = 0;
  std::uint64_t bad_length = 0;
  std::uint64_t bad_incompat_flags = 0;
  std::uint64_t inbox_dropped = 0;       // frames dropped because the loop thread fell behind
  std::uint64_t frames_handled = 0;      // frames the loop thread processed
  std::uint64_t wrong_target = 0;        // addressed to another system or component: ignored
  std::uint64_t unhandled_messages = 0;  // valid frames of messages the endpoint does not act on
  std::uint64_t rejected_inputs = 0;  // malformed or unusable values (NaN setpoint, bad seq, ...)
  std::uint64_t commands = 0;         // COMMAND_LONG/COMMAND_INT/SET_MODE handled (each acked)
  std::uint64_t frames_sent = 0;      // frames queued to clients
  std::uint64_t frames_dropped_full = 0;  // frames dropped because a client's buffer was full
  // MAVLink 2 signing, while the vehicle has a key (ignored frames, none of them handled):
  std::uint64_t bad_signature = 0;      // signed with another key (or altered)
  std::uint64_t unsigned_rejected = 0;  // unsigned (or MAVLink 1), other than RADIO_STATUS / RADIO
  std::uint64_t replayed = 0;  // correctly signed but not newer than the stream's last frame
  // connections that arrived while the process was out of file descriptors: accepted on the spare
  // descriptor and closed at once (the listener would otherwise stay readable and the I/O thread
  // spin)
  std::uint64_t fd_exhausted_accepts = 0;
};

class MavlinkServer {
 public:
  // Opens one listening socket per vehicle of sim (and its UDP links) and serves them on io_loop if
  // given (it must outlive the server; its owner starts it), else on an I/O thread of its own,
  // started here; schedule() registers its control-step work (queued messages handled, telemetry
  // produced). Throws std::runtime_error naming the address and port when a socket cannot be bound
  // (startup error). Call on the loop thread (or before the loop runs); sim must outlive the
  // server's use of the loop.
  MavlinkServer(sim::Simulation& sim, const EndpointConfig& config,
                net::EventLoop* io_loop = nullptr);
  // Stops serving (its own I/O thread, if it has one) and closes every socket; queued tasks and the
  // observer become no-ops. Loop thread or after the loop stopped.
  ~MavlinkServer();
  MavlinkServer(const MavlinkServer&) = delete;
  MavlinkServer& operator=(const MavlinkServer&) = delete;

  // Registers the endpoints' control step as "mavlink" in steps' post-control phase; after the
  // server is destroyed it does nothing. Before the loop starts.
  void schedule(sim::StepSchedule& steps);

  std::size_t vehicle_count() const;              // Thread-safe.
  std::uint16_t port(std::size_t vehicle) const;  // The bound TCP port (useful with base_port 0; 0
                                                  // with no TCP). Thread-safe.
  // The local UDP port of a vehicle's k-th UDP link (config.udp[vehicle][k]). Thread-safe.
  std::uint16_t udp_port(std::size_t vehicle, std::size_t k) const;
  EndpointStats stats(std::size_t vehicle) const;       // Thread-safe.
  std::size_t client_count(std::size_t vehicle) const;  // Connected clients. Thread-safe.
  // The gimbal pointing last commanded over MAVLink for a vehicle. Loop thread only.
  const GimbalState& gimbal(std::size_t vehicle) const;
  const EndpointConfig& config() const;  // Thread-safe.

  // Fault injection (the sim API's link_drop): while a vehicle's link is down its endpoint neither
  // delivers bytes to its clients (telemetry produced meanwhile is discarded) nor accepts any
  // (bytes received are read and discarded, so no GCS heartbeat reaches the flight controller: its
  // GCS failsafe acts). Connections stay open. Thread-safe. False if there is no such vehicle.
  bool set_link_down(std::size_t vehicle, bool down);
  bool link_down(std::size_t vehicle) const;  // Thread-safe.
  // Has the endpoint handled (parsed and queued for the loop thread's next control step) the
  // message with MAVLink sequence number seq, or one up to 127 later (mod 256), on some client
  // connection of the vehicle? Per connection the last handled seq is kept (the lockstep contract's
  // mavlink_seq). Thread-safe.
  bool seq_processed(std::size_t vehicle, std::uint8_t seq) const;
  // Called on the I/O thread after a read that handled messages (so seq_processed may have become
  // true): the lockstep gate waiting for a `done`'s mavlink_seq wakes at once instead of polling.
  // Any thread; null: none.
  void set_seq_listener(std::function<void()> listener);
  // Blocks until the I/O thread has written to the sockets every byte queued for any client before
  // the call (telemetry and replies of the control steps so far), so that the sim API can announce
  // a lockstep tick only after them. A client whose socket buffer is full (it does not read) is not
  // waited for; the wait is also bounded by timeout_s of wall time (false then, or when the server
  // is stopping). Any thread but the I/O thread; in practice the loop thread, in the control gate.
  bool flush_queued(double timeout_s = 2.0);
  // How many times the I/O thread was asked to wake up (an eventfd write each, fewer when it is
  // behind and one write covers several): only control steps that queued a frame, handled client
  // input, or a flush or link change ask. For tests and benches.
  std::uint64_t io_wakeups() const;

  struct Core;

 private:
  std::shared_ptr<Core> core_;
};

}  // namespace uavsim::server::mavlink
