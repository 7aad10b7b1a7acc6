#include "mavlink/vehicle_link.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>

#include "mavlink/input_limits.hpp"
#include "uavsim/common/angles.hpp"

namespace uavsim::server::mavlink {

EndpointStats StatCounters::snapshot() const {
  auto r = [](const std::atomic<std::uint64_t>& c) { return c.load(std::memory_order_relaxed); };
  EndpointStats s;
  s.clients_accepted = r(clients_accepted);
  s.clients_closed = r(clients_closed);
  s.bytes_received = r(bytes_received);
  s.bytes_sent = r(bytes_sent);
  s.frames_received = r(frames_received);
  s.bytes_discarded = r(bytes_discarded);
  s.bad_crc = r(bad_crc);
  s.unknown_msgid = r(unknown_msgid);
  s.bad_length = r(bad_length);
  s.bad_incompat_flags = r(bad_incompat_flags);
  s.inbox_dropped = r(inbox_dropped);
  s.frames_handled = r(frames_handled);
  s.wrong_target = r(wrong_target);
  s.unhandled_messages = r(unhandled_messages);
  s.rejected_inputs = r(rejected_inputs);
  s.commands = r(commands);
  s.frames_sent = r(frames_sent);
  s.frames_dropped_full = r(frames_dropped_full);
  s.bad_signature = r(bad_signature);
  s.unsigned_rejected = r(unsigned_rejected);
  s.replayed = r(replayed);
  s.fd_exhausted_accepts = r(fd_exhausted_accepts);
  return s;
}

VehicleLink::VehicleLink(sim::Simulation& sim, std::size_t vehicle, const EndpointConfig& config,
                         StatCounters& stats, SigningKeyCell& signing_cell)
    : sim_(sim), vehicle_(vehicle), config_(config), stats_(stats), signing_cell_(signing_cell) {
  // MAV_TYPE from the rotor count, as ArduPilot's motors matrix reports it
  const std::size_t rotors = sim.airframe(vehicle).rotors.size();
  const MavType type =
      rotors == 6 ? MavType::Hexarotor : (rotors == 8 ? MavType::Octorotor : MavType::Quadrotor);
  mav_type_ = static_cast<std::uint8_t>(to_underlying(type));
  if (const auto id = sim.fc(vehicle).param("SYSID_THISMAV")) sysid_ = static_cast<std::uint8_t>(*id);
  if (config.auto_sysid) sysid_ = static_cast<std::uint8_t>(std::min<std::size_t>(vehicle + 1, 255));
  if (!config.tlog_dir.empty()) {
    tlog_ = std::make_unique<TlogWriter>(config.tlog_dir + "/" + sim.vehicle_name(vehicle) + ".tlog");
  }
  if (config.signing_key) {
    // no SETUP_SIGNING timestamp: start from the wall clock, as a client's own signing clock does
    const auto unix_us = std::chrono::duration_cast<std::chrono::microseconds>(
        std::chrono::system_clock::now().time_since_epoch());
    set_signing(*config.signing_key, signing_timestamp_from_unix_us(static_cast<std::uint64_t>(unix_us.count())));
  }
}

void VehicleLink::set_signing(const std::optional<SecretKey>& key, std::uint64_t initial_timestamp_10us) {
  const bool all_zero = !key || std::all_of(key->begin(), key->end(), [](std::uint8_t b) { return b == 0; });
  signing_key_ = all_zero ? std::nullopt : key;
  signing_initial_10us_ = initial_timestamp_10us;
  signing_set_s_ = now_s();
  signing_cell_.set(signing_key_);
}

std::uint32_t VehicleLink::time_boot_ms() const {
  return static_cast<std::uint32_t>(std::llround(sim_.time_s() * 1000.0));
}

VehicleLink::Link* VehicleLink::find_link(std::uint64_t client) {
  for (Link& l : links_) {
    if (l.id == client) return &l;
  }
  return nullptr;
}

void VehicleLink::log_received(std::span<const std::uint8_t> frame) {
  if (tlog_) tlog_->write(now_s(), frame);
}

void VehicleLink::push_frame(Link& link, std::span<const std::uint8_t> frame) {
  if (link.outbox->push(frame)) {
    queued_ = true;
    StatCounters::add(stats_.frames_sent);
    if (tlog_) tlog_->write(now_s(), frame);
  } else {
    StatCounters::add(stats_.frames_dropped_full);
  }
}

bool VehicleLink::addressed_to_us(int target_system, int target_component) const {
  // broadcast (0) or our system; component 0 or the autopilot
  if (target_system != 0 && target_system != sysid_) return false;
  return target_component == 0 || target_component == kCompIdAutopilot;
}

void VehicleLink::on_connect(std::uint64_t client, std::shared_ptr<Outbox> outbox) {
  Link link;
  link.id = client;
  link.outbox = std::move(outbox);
  link.streams = default_streams();
  // like ArduPilot's per-channel link ids: the lowest id no connected client uses
  for (int id = 0; id < 256; ++id) {
    if (std::none_of(links_.begin(), links_.end(), [id](const Link& l) { return l.link_id == id; })) {
      link.link_id = static_cast<std::uint8_t>(id);
      break;
    }
  }
  const double t = now_s();
  for (Stream& s : link.streams) s.next_due_s = t + s.interval_s;
  links_.push_back(std::move(link));
  // start the stream with a MAVLink 2 heartbeat, so version-sniffing clients (pymavlink) pick v2
  send_heartbeat(links_.back());
}

void VehicleLink::on_disconnect(std::uint64_t client) {
  std::erase_if(links_, [client](const Link& l) { return l.id == client; });
}

void VehicleLink::on_frame(std::uint64_t client, const Frame& f, fc::FlightController& fc) {
  Link* link_ptr = find_link(client);
  if (link_ptr == nullptr) return;
  Link& link = *link_ptr;
  StatCounters::add(stats_.frames_handled);
  // answer each client in the MAVLink version it last spoke
  link.version = f.version;
  link.peer_sysid = f.sysid;
  link.peer_compid = f.compid;

  auto wrong_target = [&](int ts, int tc) {
    if (addressed_to_us(ts, tc)) return false;
    StatCounters::add(stats_.wrong_target);
    return true;
  };

  switch (f.msgid) {
    case msg::Heartbeat::kId: {
      // any heartbeat from a ground station keeps the GCS-loss failsafe fed
      const auto m = msg::Heartbeat::decode(f.payload.data());
      if (m.type == to_underlying(MavType::Gcs) || m.autopilot == to_underlying(MavAutopilot::Invalid)) {
        fc.on_gcs_heartbeat(now_s());
      }
      break;
    }
    case msg::CommandLong::kId: {
      const auto m = msg::CommandLong::decode(f.payload.data());
      if (wrong_target(m.target_system, m.target_component)) break;
      CommandArgs c;
      c.command = m.command;
      c.p = {m.param1, m.param2, m.param3, m.param4, m.param5, m.param6, m.param7};
      StatCounters::add(stats_.commands);
      ack_command(link, f, m.command, handle_command(link, c, fc));
      break;
    }
    case msg::CommandInt::kId: {
      const auto m = msg::CommandInt::decode(f.payload.data());
      if (wrong_target(m.target_system, m.target_component)) break;
      CommandArgs c;
      c.command = m.command;
      c.is_int = true;
      c.frame = m.frame;
      c.x = m.x;
      c.y = m.y;
      c.p = {m.param1, m.param2, m.param3, m.param4, m.x / 1e7, m.y / 1e7, m.z};
      StatCounters::add(stats_.commands);
      ack_command(link, f, m.command, handle_command(link, c, fc));
      break;
    }
    case msg::SetMode::kId: {
      const auto m = msg::SetMode::decode(f.payload.data());
      if (wrong_target(m.target_system, 0)) break;
      StatCounters::add(stats_.commands);
      CommandArgs c;
      c.command = to_underlying(MavCmd::DoSetMode);  // the same path as the command
      c.p[0] = m.base_mode;
      c.p[1] = m.custom_mode;
      ack_command(link, f, msg::SetMode::kId, handle_command(link, c, fc));
      break;
    }
    case msg::SetPositionTargetLocalNed::kId: {
      const auto m = msg::SetPositionTargetLocalNed::decode(f.payload.data());
      if (wrong_target(m.target_system, m.target_component)) break;
      handle_set_position_target_local(m, fc);
      break;
    }
    case msg::SetPositionTargetGlobalInt::kId: {
      const auto m = msg::SetPositionTargetGlobalInt::decode(f.payload.data());
      if (wrong_target(m.target_system, m.target_component)) break;
      handle_set_position_target_global(m, fc);
      break;
    }
    case msg::SetAttitudeTarget::kId: {
      const auto m = msg::SetAttitudeTarget::decode(f.payload.data());
      if (wrong_target(m.target_system, m.target_component)) break;
      handle_set_attitude_target(m, fc);
      break;
    }
    case msg::GimbalManagerSetPitchyaw::kId: {
      const auto m = msg::GimbalManagerSetPitchyaw::decode(f.payload.data());
      if (m.target_system != 0 && m.target_system != sysid_) {
        StatCounters::add(stats_.wrong_target);
        break;
      }
      constexpr double kRadToDeg = 180.0 / common::kPi;
      // NaN leaves an angle as it is (MAVLink's convention); anything else must be a sane number
      const auto bad = [](float v, double limit) { return !std::isnan(v) && !limits::within(v, limit); };
      if (bad(m.pitch, limits::kYaw_rad) || bad(m.yaw, limits::kYaw_rad) || bad(m.pitch_rate, limits::kRate_rad_s) ||
          bad(m.yaw_rate, limits::kRate_rad_s)) {
        StatCounters::add(stats_.rejected_inputs);
        break;
      }
      if (std::isfinite(m.pitch)) gimbal_.pitch_deg = m.pitch * kRadToDeg;
      if (std::isfinite(m.yaw)) gimbal_.yaw_deg = m.yaw * kRadToDeg;
      gimbal_.pitch_rate_deg_s = std::isfinite(m.pitch_rate) ? m.pitch_rate * kRadToDeg : 0.0;
      gimbal_.yaw_rate_deg_s = std::isfinite(m.yaw_rate) ? m.yaw_rate * kRadToDeg : 0.0;
      gimbal_.yaw_earth_frame = (m.flags & to_underlying(GimbalManagerFlags::YawLock)) != 0;
      gimbal_.stamp_s = now_s();
      break;
    }
    case msg::ParamRequestList::kId: {
      const auto m = msg::ParamRequestList::decode(f.payload.data());
      if (wrong_target(m.target_system, m.target_component)) break;
      handle_param_request_list(link);
      break;
    }
    case msg::ParamRequestRead::kId: {
      const auto m = msg::ParamRequestRead::decode(f.payload.data());
      if (wrong_target(m.target_system, m.target_component)) break;
      handle_param_request_read(link, m);
      break;
    }
    case msg::ParamSet::kId: {
      const auto m = msg::ParamSet::decode(f.payload.data());
      if (wrong_target(m.target_system, m.target_component)) break;
      handle_param_set(m, fc);
      break;
    }
    case msg::MissionCount::kId: {
      const auto m = msg::MissionCount::decode(f.payload.data());
      if (wrong_target(m.target_system, m.target_component)) break;
      handle_mission_count(link, f, m);
      break;
    }
    case msg::MissionItemInt::kId: {
      const auto m = msg::MissionItemInt::decode(f.payload.data());
      if (wrong_target(m.target_system, m.target_component)) break;
      link.mission_int = true;
      handle_mission_item(link, f, m, true, fc);
      break;
    }
    case msg::MissionItem::kId: {
      const auto m = msg::MissionItem::decode(f.payload.data());
      if (wrong_target(m.target_system, m.target_component)) break;
      // carry the float item in the INT struct: x/y as degrees * 1e7 keeps 1 cm resolution; a
      // latitude/longitude out of range would overflow that conversion, so it is refused first
      if (!limits::valid_lat_lon(m.x, m.y)) {
        StatCounters::add(stats_.rejected_inputs);
        reject_mission_item(link, f);
        break;
      }
      msg::MissionItemInt i;
      i.param1 = m.param1;
      i.param2 = m.param2;
      i.param3 = m.param3;
      i.param4 = m.param4;
      i.x = static_cast<std::int32_t>(std::llround(static_cast<double>(m.x) * 1e7));
      i.y = static_cast<std::int32_t>(std::llround(static_cast<double>(m.y) * 1e7));
      i.z = m.z;
      i.seq = m.seq;
      i.command = m.command;
      i.target_system = m.target_system;
      i.target_component = m.target_component;
      i.frame = m.frame;
      i.current = m.current;
      i.autocontinue = m.autocontinue;
      i.mission_type = m.mission_type;
      handle_mission_item(link, f, i, false, fc);
      break;
    }
    case msg::MissionRequestInt::kId: {
      const auto m = msg::MissionRequestInt::decode(f.payload.data());
      if (wrong_target(m.target_system, m.target_component)) break;
      link.mission_int = true;
      handle_mission_request(link, f, m.seq, true, fc);
      break;
    }
    case msg::MissionRequest::kId: {
      const auto m = msg::MissionRequest::decode(f.payload.data());
      if (wrong_target(m.target_system, m.target_component)) break;
      handle_mission_request(link, f, m.seq, false, fc);
      break;
    }
    case msg::MissionRequestList::kId: {
      const auto m = msg::MissionRequestList::decode(f.payload.data());
      if (wrong_target(m.target_system, m.target_component)) break;
      handle_mission_request_list(link, f, m.mission_type, fc);
      break;
    }
    case msg::MissionClearAll::kId: {
      const auto m = msg::MissionClearAll::decode(f.payload.data());
      if (wrong_target(m.target_system, m.target_component)) break;
      handle_mission_clear_all(link, f, m.mission_type, fc);
      break;
    }
    case msg::MissionSetCurrent::kId: {
      const auto m = msg::MissionSetCurrent::decode(f.payload.data());
      if (wrong_target(m.target_system, m.target_component)) break;
      handle_mission_set_current(m.seq, fc);
      break;
    }
    case msg::MissionAck::kId:
      break;  // end of a download: nothing is held per download
    case msg::RequestDataStream::kId: {
      const auto m = msg::RequestDataStream::decode(f.payload.data());
      if (wrong_target(m.target_system, m.target_component)) break;
      handle_request_data_stream(link, m);
      break;
    }
    case msg::Timesync::kId:
      handle_timesync(link, msg::Timesync::decode(f.payload.data()));
      break;
    case msg::SetupSigning::kId: {
      // ArduPilot takes it from any client and applies it to every link at once (GCS_Signing.cpp); once
      // signing is on, only a signed SETUP_SIGNING gets here (the I/O thread drops unsigned frames)
      const auto m = msg::SetupSigning::decode(f.payload.data());
      if (wrong_target(m.target_system, m.target_component)) break;
      set_signing(m.secret_key, m.initial_timestamp);
      break;
    }
    case msg::RcChannelsOverride::kId: {
      const auto m = msg::RcChannelsOverride::decode(f.payload.data());
      if (wrong_target(m.target_system, m.target_component)) break;
      handle_rc_override(f, m, fc);
      break;
    }
    case msg::ManualControl::kId: {
      const auto m = msg::ManualControl::decode(f.payload.data());
      if (wrong_target(m.target, 0)) break;
      handle_manual_control(f, m, fc);
      break;
    }
    case msg::AutopilotVersionRequest::kId: {
      const auto m = msg::AutopilotVersionRequest::decode(f.payload.data());
      if (wrong_target(m.target_system, m.target_component)) break;
      send_autopilot_version(link);
      break;
    }
    default:
      StatCounters::add(stats_.unhandled_messages);
      break;
  }
}

void VehicleLink::on_control_step() {
  fc::FlightController& fc = sim_.fc(vehicle_);
  // status texts and reached mission items are events: drain them even with nobody listening
  for (const fc::StatusText& s : fc.drain_status_texts()) {
    if (config_.on_status_text) config_.on_status_text(vehicle_, s.severity, s.text);
    send_status_text(s.severity, s.text);
  }
  for (int seq : fc.drain_reached_items()) {
    msg::MissionItemReached r;
    r.seq = static_cast<std::uint16_t>(seq);
    broadcast(r);
  }
  if (links_.empty()) return;
  const double t = now_s();
  for (Link& link : links_) {
    for (std::uint32_t id : link.one_shot) send_message_by_id(link, id);
    link.one_shot.clear();
    send_due_streams(link, t);
    service_mission_upload(link, t);
    service_param_download(link);
  }
  // TIMESYNC: ArduPilot broadcasts its own request every ~10 s (ts1 = now_ns + sysid)
  if (t >= next_timesync_s_) {
    next_timesync_s_ = t + 10.0;
    msg::Timesync ts;
    ts.tc1 = 0;
    ts.ts1 = static_cast<std::int64_t>(std::llround(t * 1e9)) + sysid_;
    broadcast(ts);
  }
}


namespace {
constexpr std::uint8_t kSysidMyGcs = 255;  // ArduPilot's SYSID_MYGCS default
}  // namespace

void VehicleLink::handle_rc_override(const Frame& f, const msg::RcChannelsOverride& m, fc::FlightController& fc) {
  if (f.sysid != kSysidMyGcs) {
    StatCounters::add(stats_.unhandled_messages);
    return;
  }
  // channels 1-4 are roll, pitch, throttle, yaw (ArduCopter's RCMAP defaults) in microseconds; 0
  // releases a channel (centred, mid throttle: no radio behind it here), UINT16_MAX leaves it as it was
  const std::uint16_t pwm[4] = {m.chan1_raw, m.chan2_raw, m.chan3_raw, m.chan4_raw};
  fc::PilotInput in = pilot_;
  double* axis[4] = {&in.roll, &in.pitch, &in.throttle, &in.yaw};
  for (int k = 0; k < 4; ++k) {
    if (pwm[k] == UINT16_MAX) continue;
    if (pwm[k] != 0 && (pwm[k] < 800 || pwm[k] > 2200)) {
      StatCounters::add(stats_.rejected_inputs);
      return;
    }
    const double us = pwm[k] == 0 ? 1500.0 : std::clamp<double>(pwm[k], 1000.0, 2000.0);
    // channel 2 high is nose up (stick back); throttle runs 1000 (0) to 2000 (1)
    *axis[k] = k == 2 ? (us - 1000.0) / 1000.0 : (us - 1500.0) / 500.0 * (k == 1 ? -1.0 : 1.0);
  }
  if (fc.set_pilot_input(in, now_s()) != fc::CommandResult::kInvalid) pilot_ = in;
}

void VehicleLink::handle_manual_control(const Frame& f, const msg::ManualControl& m, fc::FlightController& fc) {
  if (f.sysid != kSysidMyGcs) {
    StatCounters::add(stats_.unhandled_messages);
    return;
  }
  // x forward, y right, r clockwise in [-1000, 1000], z throttle in [0, 1000] (ArduPilot's reading);
  // INT16_MAX marks an axis as unused: it keeps its value
  fc::PilotInput in = pilot_;
  const std::int16_t raw[4] = {m.y, m.x, m.z, m.r};
  double* axis[4] = {&in.roll, &in.pitch, &in.throttle, &in.yaw};
  for (int k = 0; k < 4; ++k) {
    if (raw[k] == INT16_MAX) continue;
    *axis[k] = k == 2 ? std::clamp(raw[k] / 1000.0, 0.0, 1.0) : std::clamp(raw[k] / 1000.0, -1.0, 1.0);
  }
  if (fc.set_pilot_input(in, now_s()) != fc::CommandResult::kInvalid) pilot_ = in;
}

}  // namespace uavsim::server::mavlink
