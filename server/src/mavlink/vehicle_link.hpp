// Internal to the endpoint: the loop-thread half of one vehicle's MAVLink endpoint. It owns the state of
// every connected client (its MAVLink version, sequence numbers, telemetry schedule, mission upload,
// parameter download) and speaks ArduCopter's protocol over the vehicle's flight controller. The protocol
// logic lives in small pure parts, each unit-tested without sockets; this class routes frames to them and
// sends what they answer:
//   command_mapper.hpp      COMMAND_LONG/INT, SET_MODE -> a typed request (fc, gimbal, link) + its ack result
//   mission_upload.hpp      the mission upload state machine (count, items in sequence, retries, timeout)
//   param_download.hpp      the paced PARAM_REQUEST_LIST download
//   telemetry_schedule.hpp  which messages each client has streamed, and when each is due
// and the link's own files:
//   vehicle_link.cpp      the router (frame -> decode -> target check -> part), sending, client bookkeeping
//   telemetry.cpp         the messages themselves, from the flight controller's estimate
//   command_handler.cpp   commands carried out, SET_POSITION_TARGET_*, SET_ATTITUDE_TARGET, sticks
//   mission_protocol.cpp  MAVLink <-> fc::MissionItem, download, guided goto, MISSION_CURRENT/REACHED
//   param_protocol.cpp    PARAM_REQUEST_READ, PARAM_SET, PARAM_VALUE
// MAVLink's conventions (NED, headings "0 = north, clockwise", degrees, degE7) are converted in these
// files; the flight controller sees ENU, FLU and radians only.
// Every method is loop-thread only.
#pragma once

#include <array>
#include <atomic>
#include <cstdint>
#include <memory>
#include <mutex>
#include <optional>
#include <utility>
#include <vector>

#include "fc/flight_controller.hpp"
#include "uavsim/common/mavlink/codec.hpp"
#include "uavsim/common/mavlink/signing.hpp"
#include "mavlink/command_mapper.hpp"
#include "mavlink/endpoint.hpp"
#include "mavlink/mission_upload.hpp"
#include "mavlink/param_download.hpp"
#include "mavlink/telemetry_schedule.hpp"
#include "uavsim/common/mavlink/generated/enums.hpp"
#include "uavsim/common/mavlink/generated/messages.hpp"
#include "mavlink/outbox.hpp"
#include "mavlink/tlog.hpp"
#include "sim/simulation.hpp"

namespace uavsim::server::mavlink {

// The link speaks the common codec: its frames, messages and enums are used unqualified here.
using namespace ::uavsim::common::mavlink;

// EndpointStats as relaxed atomics, written by both threads.
struct StatCounters {
  std::atomic<std::uint64_t> clients_accepted{0}, clients_closed{0}, bytes_received{0}, bytes_sent{0},
      frames_received{0}, bytes_discarded{0}, bad_crc{0}, unknown_msgid{0}, bad_length{0},
      bad_incompat_flags{0}, inbox_dropped{0}, frames_handled{0}, wrong_target{0}, unhandled_messages{0},
      rejected_inputs{0}, commands{0}, frames_sent{0}, frames_dropped_full{0}, bad_signature{0},
      unsigned_rejected{0}, replayed{0}, fd_exhausted_accepts{0};
  std::atomic<std::uint64_t> clients_now{0};

  static void add(std::atomic<std::uint64_t>& c, std::uint64_t n = 1) {
    c.fetch_add(n, std::memory_order_relaxed);
  }
  EndpointStats snapshot() const;
};

// A vehicle's MAVLink 2 signing key as the I/O thread needs it to check incoming frames: the loop thread
// sets it (SETUP_SIGNING), the I/O thread reconfigures a client's parser when generation() moves.
// Thread-safe.
class SigningKeyCell {
 public:
  void set(const std::optional<SecretKey>& key) {
    std::lock_guard lock(mutex_);
    key_ = key;
    generation_.fetch_add(1, std::memory_order_release);
  }
  std::optional<SecretKey> get() const {
    std::lock_guard lock(mutex_);
    return key_;
  }
  std::uint64_t generation() const { return generation_.load(std::memory_order_acquire); }

 private:
  mutable std::mutex mutex_;
  std::optional<SecretKey> key_;  // guarded by mutex_
  std::atomic<std::uint64_t> generation_{0};
};

// Unsigned messages ArduPilot accepts on a signed link (GCS_Signing.cpp accept_unsigned_callback): the
// radios' own status reports, which a radio cannot sign.
inline bool accepted_unsigned(std::uint32_t msgid) {
  return msgid == msg::RadioStatus::kId || msgid == 166 /* RADIO (ardupilotmega; no struct generated) */;
}

inline constexpr std::uint8_t kCompIdAutopilot = to_underlying(MavComponent::CompIdAutopilot1);

class VehicleLink {
 public:
  // signing_cell receives the vehicle's signing key (config.signing_key at once, then SETUP_SIGNING's)
  VehicleLink(sim::Simulation& sim, std::size_t vehicle, const EndpointConfig& config, StatCounters& stats,
              SigningKeyCell& signing_cell);

  // client bookkeeping, from the I/O thread's events
  void on_connect(std::uint64_t client, std::shared_ptr<Outbox> outbox);
  void on_disconnect(std::uint64_t client);
  // one checksum-valid frame from a client; commands act on fc
  void on_frame(std::uint64_t client, const Frame& frame, fc::FlightController& fc);
  // after every control step: due telemetry, status texts, reached items, transfer retries
  void on_control_step();

  // a frame a client sent, for the telemetry log (before on_frame)
  void log_received(std::span<const std::uint8_t> frame);

  // whether a frame was queued for a client since the last call: the endpoint wakes its I/O thread only
  // then
  bool take_queued() { return std::exchange(queued_, false); }
  const GimbalState& gimbal() const { return gimbal_; }
  bool signing() const { return signing_key_.has_value(); }

 private:
  struct Link {
    std::uint64_t id = 0;
    std::shared_ptr<Outbox> outbox;
    Version version = Version::kV2;
    std::uint8_t seq = 0;
    std::uint8_t peer_sysid = 255;
    std::uint8_t peer_compid = 190;
    TelemetrySchedule streams{0.0};
    std::vector<std::uint32_t> one_shot;  // REQUEST_MESSAGE answers queued for the next step
    MissionUpload upload;
    bool mission_int = false;    // the client has used *_INT mission messages: request items as INT
    ParamDownload params;
    std::uint8_t link_id = 0;    // signing link id: the lowest one free when the client connected
    TimestampSource signing_timestamps;
  };

  // --- vehicle_link.cpp ---
  Link* find_link(std::uint64_t client);
  template <class Msg>
  void send(Link& link, const Msg& msg) {
    FrameHeader header;
    header.sysid = sysid_;
    header.compid = kCompIdAutopilot;
    header.seq = link.seq;
    header.version = link.version;
    // the C library signs MAVLink 2 only; a MAVLink 1 link stays unsigned
    if (signing_key_ && link.version == Version::kV2) {
      header.signing = SigningParams{*signing_key_, link.link_id,
                                     link.signing_timestamps.next(signing_now_10us())};
    }
    std::array<std::uint8_t, kMaxFrameLen> buf;
    const std::size_t n = encode_into(header, msg, buf);
    if (n == 0) return;  // e.g. a message id above 255 on a MAVLink 1 link
    ++link.seq;
    push_frame(link, {buf.data(), n});
  }
  void push_frame(Link& link, std::span<const std::uint8_t> frame);
  template <class Msg>
  void broadcast(const Msg& msg) {
    for (Link& l : links_) send(l, msg);
  }
  bool addressed_to_us(int target_system, int target_component) const;
  // the router's one step: decodes Msg from f and hands it to handle when it is addressed to this vehicle
  // (target_system 0 or ours; target_component 0 or the autopilot, or any with kAnyComponent), counts
  // wrong_target otherwise
  static constexpr bool kAnyComponent = true;
  template <class Msg, bool any_component = false, class Handle>
  void route(const Frame& f, Handle&& handle) {
    const Msg m = Msg::decode(f.payload.data());
    int target_system = 0, target_component = 0;
    if constexpr (requires { m.target_system; }) {
      target_system = m.target_system;
    } else {
      target_system = m.target;  // MANUAL_CONTROL
    }
    if constexpr (!any_component && requires { m.target_component; }) target_component = m.target_component;
    if (!addressed_to_us(target_system, target_component)) {
      StatCounters::add(stats_.wrong_target);
      return;
    }
    handle(m);
  }
  // SETUP_SIGNING: the key and initial timestamp (an all-zero key turns signing off)
  void set_signing(const std::optional<SecretKey>& key, std::uint64_t initial_timestamp_10us);
  // the signing clock (10 us since 2015): the initial timestamp advanced by sim time, or the simulated
  // GPS time when later (ArduPilot's update_signing_timestamp on GPS lock)
  std::uint64_t signing_now_10us() const;
  double now_s() const { return sim_.time_s(); }
  std::uint32_t time_boot_ms() const;

  // --- telemetry.cpp ---
  bool send_message_by_id(Link& link, std::uint32_t msgid);  // false: not a message we can produce
  bool can_send(std::uint32_t msgid) const;
  msg::Heartbeat heartbeat() const;
  void send_heartbeat(Link& link);
  void send_home(Link& link);
  void send_autopilot_version(Link& link);
  void send_status_text(int severity, std::string_view text);
  void handle_request_data_stream(Link& link, const msg::RequestDataStream& m);
  void handle_timesync(Link& link, const msg::Timesync& m);
  Geodetic geodetic_of_enu(const Eigen::Vector3d& p_enu) const;
  Eigen::Vector3d enu_of_geodetic(const Geodetic& g) const;

  // --- command_handler.cpp ---
  // a command counted, carried out and acked with ack_id
  void run_command(Link& link, const Frame& f, std::uint16_t ack_id, const CommandArgs& c, fc::FlightController& fc);
  std::uint8_t handle_command(Link& link, const CommandArgs& c, fc::FlightController& fc);
  std::uint8_t handle_link_request(Link& link, const LinkRequest& request, fc::FlightController& fc);
  void ack_command(Link& link, const Frame& frame, std::uint16_t command, std::uint8_t result);
  void handle_set_position_target_local(const msg::SetPositionTargetLocalNed& m, fc::FlightController& fc);
  void handle_set_position_target_global(const msg::SetPositionTargetGlobalInt& m, fc::FlightController& fc);
  void apply_setpoint(std::uint16_t mask, int frame, std::optional<Eigen::Vector3d> pos_ned,
                      const Eigen::Vector3d& vel_ned, const Eigen::Vector3d& acc_ned, double yaw_ned,
                      double yaw_rate_ned, fc::FlightController& fc);
  void handle_set_attitude_target(const msg::SetAttitudeTarget& m, fc::FlightController& fc);
  void handle_gimbal_pitchyaw(const msg::GimbalManagerSetPitchyaw& m);
  // RC_CHANNELS_OVERRIDE and MANUAL_CONTROL: the pilot's sticks (ArduCopter takes them from its own
  // ground station only, SYSID_MYGCS 255)
  void handle_rc_override(const Frame& f, const msg::RcChannelsOverride& m, fc::FlightController& fc);
  void handle_manual_control(const Frame& f, const msg::ManualControl& m, fc::FlightController& fc);
  void hold_position(fc::FlightController& fc);

  // --- mission_protocol.cpp ---
  // True when a client other than link has a mission upload in progress.
  bool upload_by_another_link(const Link& link) const;
  void handle_mission_count(Link& link, const Frame& f, const msg::MissionCount& m);
  // answers an item whose numbers could not be read with MISSION_ACK ERROR, ending an upload in progress
  void reject_mission_item(Link& link, const Frame& f);
  void handle_mission_item(Link& link, const Frame& f, const msg::MissionItemInt& m, bool is_int,
                           fc::FlightController& fc);
  // MISSION_ITEM (float lat/lon): as MISSION_ITEM_INT, refused when it cannot be carried in one
  void handle_mission_item_float(Link& link, const Frame& f, const msg::MissionItem& m, fc::FlightController& fc);
  void handle_mission_request(Link& link, const Frame& f, int seq, bool want_int, fc::FlightController& fc);
  void handle_mission_request_list(Link& link, const Frame& f, int mission_type, fc::FlightController& fc);
  void handle_mission_clear_all(Link& link, const Frame& f, int mission_type, fc::FlightController& fc);
  void handle_mission_set_current(int seq, fc::FlightController& fc);
  void send_mission_request(Link& link, int seq);
  // does what an upload step asks: set the mission, request an item, ack to sysid/compid
  void apply_upload_step(Link& link, UploadStep step, std::uint8_t sysid, std::uint8_t compid);
  void send_mission_ack(Link& link, std::uint8_t sysid, std::uint8_t compid, std::uint8_t result,
                        std::uint8_t mission_type = 0);
  void service_mission_upload(Link& link, double t);
  msg::MissionCurrent mission_current() const;
  std::optional<fc::MissionItem> mission_item_from_mavlink(const msg::MissionItemInt& m, bool is_int,
                                                           std::uint8_t* error) const;
  msg::MissionItemInt mission_item_to_mavlink(const fc::MissionItem& item, int seq) const;
  void guided_goto(Link& link, const Frame& f, const msg::MissionItemInt& m, bool is_int,
                   fc::FlightController& fc);

  // --- param_protocol.cpp ---
  void handle_param_request_list(Link& link);
  void handle_param_request_read(Link& link, const msg::ParamRequestRead& m);
  void handle_param_set(const msg::ParamSet& m, fc::FlightController& fc);
  void send_param(Link& link, std::size_t index);
  void service_param_download(Link& link);

  sim::Simulation& sim_;
  const std::size_t vehicle_;
  const EndpointConfig& config_;
  StatCounters& stats_;
  std::vector<Link> links_;
  bool queued_ = false;  // a frame queued since take_queued() (loop thread only)
  GimbalState gimbal_;
  SigningKeyCell& signing_cell_;
  std::optional<SecretKey> signing_key_;
  std::uint64_t signing_initial_10us_ = 0;
  double signing_set_s_ = 0.0;  // sim time of the last set_signing()
  std::uint8_t sysid_ = 1;
  std::uint8_t mav_type_ = to_underlying(MavType::Quadrotor);
  double next_timesync_s_ = 0.0;
  std::uint16_t next_text_id_ = 1;  // STATUSTEXT chunk ids
  fc::PilotInput pilot_;  // the sticks as last overridden (a channel sent as "ignore" keeps its value)
  std::unique_ptr<TlogWriter> tlog_;  // config.tlog_dir's log of this vehicle, if any
  bool tlog_error_said_ = false;      // its write failure was said (once)
  // frame into the tlog, if any; a write failure said on stderr once
  void log_frame(std::span<const std::uint8_t> frame);
};

}  // namespace uavsim::server::mavlink
