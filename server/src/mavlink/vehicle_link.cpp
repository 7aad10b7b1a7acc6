#include "mavlink/vehicle_link.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>


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

void VehicleLink::log_frame(std::span<const std::uint8_t> frame) {
  if (!tlog_) return;
  tlog_->write(now_s(), frame);
  if (!tlog_error_said_ && !tlog_->error().empty()) {
    // a full disk or the file size limit: said once (the launcher ends the run on it); the frames
    // logged before stay whole (RecordFile cuts a partly written batch off)
    tlog_error_said_ = true;
    std::fprintf(stderr, "uavsim-server: the tlog stops here: %s\n", tlog_->error().c_str());
  }
}

void VehicleLink::log_received(std::span<const std::uint8_t> frame) { log_frame(frame); }

void VehicleLink::push_frame(Link& link, std::span<const std::uint8_t> frame) {
  if (link.outbox->push(frame)) {
    queued_ = true;
    StatCounters::add(stats_.frames_sent);
    log_frame(frame);
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
  link.streams = TelemetrySchedule(now_s());
  // like ArduPilot's per-channel link ids: the lowest id no connected client uses
  for (int id = 0; id < 256; ++id) {
    if (std::none_of(links_.begin(), links_.end(), [id](const Link& l) { return l.link_id == id; })) {
      link.link_id = static_cast<std::uint8_t>(id);
      break;
    }
  }
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

  // route: decode, drop what is addressed to another vehicle, hand the message to its part
  switch (f.msgid) {
    case msg::Heartbeat::kId: {
      // any heartbeat from a ground station keeps the GCS-loss failsafe fed
      const auto m = msg::Heartbeat::decode(f.payload.data());
      if (m.type == to_underlying(MavType::Gcs) || m.autopilot == to_underlying(MavAutopilot::Invalid)) {
        fc.on_gcs_heartbeat(now_s());
      }
      return;
    }
    // commands, acked with the command's id (SET_MODE: the message's)
    case msg::CommandLong::kId:
      return route<msg::CommandLong>(f, [&](const auto& m) { run_command(link, f, m.command, command_args(m), fc); });
    case msg::CommandInt::kId:
      return route<msg::CommandInt>(f, [&](const auto& m) { run_command(link, f, m.command, command_args(m), fc); });
    case msg::SetMode::kId:
      return route<msg::SetMode>(f, [&](const auto& m) { run_command(link, f, msg::SetMode::kId, command_args(m), fc); });
    // guided setpoints and the camera gimbal
    case msg::SetPositionTargetLocalNed::kId:
      return route<msg::SetPositionTargetLocalNed>(f, [&](const auto& m) { handle_set_position_target_local(m, fc); });
    case msg::SetPositionTargetGlobalInt::kId:
      return route<msg::SetPositionTargetGlobalInt>(f, [&](const auto& m) { handle_set_position_target_global(m, fc); });
    case msg::SetAttitudeTarget::kId:
      return route<msg::SetAttitudeTarget>(f, [&](const auto& m) { handle_set_attitude_target(m, fc); });
    case msg::GimbalManagerSetPitchyaw::kId:  // any component: the gimbal's own, or the autopilot's
      return route<msg::GimbalManagerSetPitchyaw, kAnyComponent>(f, [&](const auto& m) { handle_gimbal_pitchyaw(m); });
    case msg::RcChannelsOverride::kId:
      return route<msg::RcChannelsOverride>(f, [&](const auto& m) { handle_rc_override(f, m, fc); });
    case msg::ManualControl::kId:
      return route<msg::ManualControl>(f, [&](const auto& m) { handle_manual_control(f, m, fc); });
    // parameters
    case msg::ParamRequestList::kId:
      return route<msg::ParamRequestList>(f, [&](const auto&) { handle_param_request_list(link); });
    case msg::ParamRequestRead::kId:
      return route<msg::ParamRequestRead>(f, [&](const auto& m) { handle_param_request_read(link, m); });
    case msg::ParamSet::kId:
      return route<msg::ParamSet>(f, [&](const auto& m) { handle_param_set(m, fc); });
    // missions
    case msg::MissionCount::kId:
      return route<msg::MissionCount>(f, [&](const auto& m) { handle_mission_count(link, f, m); });
    case msg::MissionItemInt::kId:
      return route<msg::MissionItemInt>(f, [&](const auto& m) {
        link.mission_int = true;
        handle_mission_item(link, f, m, true, fc);
      });
    case msg::MissionItem::kId:
      return route<msg::MissionItem>(f, [&](const auto& m) { handle_mission_item_float(link, f, m, fc); });
    case msg::MissionRequestInt::kId:
      return route<msg::MissionRequestInt>(f, [&](const auto& m) {
        link.mission_int = true;
        handle_mission_request(link, f, m.seq, true, fc);
      });
    case msg::MissionRequest::kId:
      return route<msg::MissionRequest>(f, [&](const auto& m) { handle_mission_request(link, f, m.seq, false, fc); });
    case msg::MissionRequestList::kId:
      return route<msg::MissionRequestList>(
          f, [&](const auto& m) { handle_mission_request_list(link, f, m.mission_type, fc); });
    case msg::MissionClearAll::kId:
      return route<msg::MissionClearAll>(f, [&](const auto& m) { handle_mission_clear_all(link, f, m.mission_type, fc); });
    case msg::MissionSetCurrent::kId:
      return route<msg::MissionSetCurrent>(f, [&](const auto& m) { handle_mission_set_current(m.seq, fc); });
    case msg::MissionAck::kId:
      return;  // end of a download: nothing is held per download
    // telemetry and the link itself
    case msg::RequestDataStream::kId:
      return route<msg::RequestDataStream>(f, [&](const auto& m) { handle_request_data_stream(link, m); });
    case msg::Timesync::kId:
      return handle_timesync(link, msg::Timesync::decode(f.payload.data()));
    case msg::SetupSigning::kId:
      // ArduPilot takes it from any client and applies it to every link at once (GCS_Signing.cpp); once
      // signing is on, only a signed SETUP_SIGNING gets here (the I/O thread drops unsigned frames)
      return route<msg::SetupSigning>(f, [&](const auto& m) { set_signing(m.secret_key, m.initial_timestamp); });
    case msg::AutopilotVersionRequest::kId:
      return route<msg::AutopilotVersionRequest>(f, [&](const auto&) { send_autopilot_version(link); });
    default:
      StatCounters::add(stats_.unhandled_messages);
      return;
  }
}

void VehicleLink::run_command(Link& link, const Frame& f, std::uint16_t ack_id, const CommandArgs& c,
                              fc::FlightController& fc) {
  StatCounters::add(stats_.commands);
  ack_command(link, f, ack_id, handle_command(link, c, fc));
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
    link.streams.take_due(t, [&](std::uint32_t msgid) { send_message_by_id(link, msgid); });
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


}  // namespace uavsim::server::mavlink
