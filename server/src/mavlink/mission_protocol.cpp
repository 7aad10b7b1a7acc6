// The MAVLink mission protocol over the flight controller's AUTO mission (docs/mavlink.md §6.2):
// upload (MISSION_COUNT -> MISSION_REQUEST[_INT] per item -> MISSION_ACK), download
// (MISSION_REQUEST_LIST -> MISSION_COUNT, MISSION_REQUEST[_INT] -> MISSION_ITEM[_INT]), clear, set
// current, and DroneKit's guided goto (MISSION_ITEM with current = 2). Item 0 is home, as in
// ArduPilot. Transfers are per client and time out in sim time: an unanswered request is repeated
// after 1 s, the upload is cancelled after 8 s of silence.
#include <algorithm>
#include <cmath>

#include "uavsim/common/angles.hpp"
#include "uavsim/common/frames.hpp"
#include "mavlink/input_limits.hpp"
#include "mavlink/vehicle_link.hpp"
#include "uavsim/common/mavlink/mission_item.hpp"

namespace uavsim::server::mavlink {

namespace frames = ::uavsim::common::frames;

namespace {

constexpr std::uint8_t result(MavMissionResult r) { return static_cast<std::uint8_t>(to_underlying(r)); }
constexpr std::uint8_t kMissionAccepted = result(MavMissionResult::Accepted);
constexpr std::uint8_t kMissionError = result(MavMissionResult::Error);
constexpr std::uint8_t kMissionUnsupportedFrame = result(MavMissionResult::UnsupportedFrame);
constexpr std::uint8_t kMissionUnsupported = result(MavMissionResult::Unsupported);
constexpr std::uint8_t kMissionInvalidSequence = result(MavMissionResult::InvalidSequence);
constexpr std::uint8_t kMissionDenied = result(MavMissionResult::Denied);

// the mission proper (no fence or rally points)
constexpr std::uint8_t kMissionTypeMission = to_underlying(MavMissionType::Mission);

// a MAV_CMD as MISSION_ITEM_INT's command field holds it
constexpr std::uint16_t mav_command(MavCmd c) { return static_cast<std::uint16_t>(to_underlying(c)); }
constexpr std::uint8_t mav_frame(MavFrame f) { return static_cast<std::uint8_t>(to_underlying(f)); }

// CONDITION_YAW's angle is a compass heading (0 = north, clockwise, degrees); the flight controller
// holds an ENU yaw (0 = east, counter-clockwise, radians): yaw = 90 deg - heading
double yaw_enu_rad_from_heading_deg(double heading_deg) { return common::kPi / 2.0 - heading_deg * common::kPi / 180.0; }
double heading_deg_from_yaw_enu_rad(double yaw_enu_rad) { return (common::kPi / 2.0 - yaw_enu_rad) * 180.0 / common::kPi; }

// the parameters each supported command uses, in a sane range (hold times, speeds, angles)
bool params_in_range(const msg::MissionItemInt& m) {
  switch (static_cast<MavCmd>(m.command)) {
    case MavCmd::NavWaypoint:  // hold time
    case MavCmd::NavLoiterTime:  // seconds
      return sim::finite_in(m.param1, 0.0, limits::kDuration_s);
    case MavCmd::DoChangeSpeed:  // speed
      return limits::within(m.param2, limits::kSpeed_m_s);
    case MavCmd::ConditionYaw:  // angle
      return limits::within(m.param1, limits::kAngle_deg);
    default:
      return true;
  }
}

}  // namespace

void VehicleLink::send_mission_ack(Link& link, std::uint8_t sysid, std::uint8_t compid, std::uint8_t result,
                                   std::uint8_t mission_type) {
  msg::MissionAck ack;
  ack.target_system = sysid;
  ack.target_component = compid;
  ack.type = result;
  ack.mission_type = mission_type;
  send(link, ack);
}

msg::MissionCurrent VehicleLink::mission_current() const {
  const fc::FlightController& fc = sim_.fc(vehicle_);
  msg::MissionCurrent m;
  m.seq = static_cast<std::uint16_t>(std::max(0, fc.mission_current()));
  m.total = static_cast<std::uint16_t>(fc.mission().empty() ? 0 : fc.mission().size() - 1);
  const MissionState state = fc.mission().size() <= 1 ? MissionState::NoMission
                             : (fc.mode() == fc::Mode::kAuto ? MissionState::Active : MissionState::NotStarted);
  m.mission_state = static_cast<std::uint8_t>(to_underlying(state));
  m.mission_mode = fc.mode() == fc::Mode::kAuto ? 1 : 0;
  return m;
}

bool VehicleLink::upload_by_another_link(const Link& link) const {
  return std::any_of(links_.begin(), links_.end(),
                     [&link](const Link& l) { return &l != &link && l.upload.active(); });
}

void VehicleLink::handle_mission_count(Link& link, const Frame& f, const msg::MissionCount& m) {
  // one upload at a time per vehicle, as ArduPilot: another client's is DENIED (the last to finish
  // used to win); the same client's new MISSION_COUNT restarts its own
  if (m.mission_type == kMissionTypeMission && upload_by_another_link(link)) {
    StatCounters::add(stats_.rejected_inputs);
    send_mission_ack(link, f.sysid, f.compid, kMissionDenied, m.mission_type);
    return;
  }
  apply_upload_step(link, link.upload.on_count(m.count, m.mission_type, now_s()), f.sysid, f.compid);
}

void VehicleLink::apply_upload_step(Link& link, UploadStep step, std::uint8_t sysid, std::uint8_t compid) {
  if (step.rejected) StatCounters::add(stats_.rejected_inputs);
  if (step.mission) sim_.fc(vehicle_).set_mission(std::move(*step.mission));
  if (step.request_seq) send_mission_request(link, *step.request_seq);
  if (step.ack) send_mission_ack(link, sysid, compid, *step.ack, step.ack_mission_type);
}

void VehicleLink::send_mission_request(Link& link, int seq) {
  // MISSION_REQUEST_INT once the client has shown it speaks INT; otherwise the legacy request, which
  // every client answers (DroneKit only understands MISSION_REQUEST)
  if (link.mission_int) {
    msg::MissionRequestInt r;
    r.seq = static_cast<std::uint16_t>(seq);
    r.target_system = link.peer_sysid;
    r.target_component = link.peer_compid;
    send(link, r);
  } else {
    msg::MissionRequest r;
    r.seq = static_cast<std::uint16_t>(seq);
    r.target_system = link.peer_sysid;
    r.target_component = link.peer_compid;
    send(link, r);
  }
}

void VehicleLink::service_mission_upload(Link& link, double t) {
  apply_upload_step(link, link.upload.on_tick(t), link.peer_sysid, link.peer_compid);
}

std::optional<fc::MissionItem> VehicleLink::mission_item_from_mavlink(const msg::MissionItemInt& m, bool is_int,
                                                                      std::uint8_t* error) const {
  (void)is_int;
  const fc::FlightController& fc = sim_.fc(vehicle_);
  fc::MissionItem item;
  // frame: global AMSL, relative to home, or terrain (treated as relative); local frames are not missions
  const bool amsl = is_one_of<MavFrame>(m.frame, {MavFrame::Global, MavFrame::GlobalInt});
  const bool relative = is_one_of<MavFrame>(m.frame, {MavFrame::GlobalRelativeAlt, MavFrame::GlobalRelativeAltInt,
                                                      MavFrame::GlobalTerrainAlt, MavFrame::GlobalTerrainAltInt});
  const bool needs_position = is_one_of<MavCmd>(
      m.command, {MavCmd::NavWaypoint, MavCmd::NavTakeoff, MavCmd::NavLand, MavCmd::NavLoiterTime});
  if (needs_position && !amsl && !relative) {
    *error = kMissionUnsupportedFrame;
    return std::nullopt;
  }
  const double lat = m.x / 1e7, lon = m.y / 1e7;
  // every number checked before use: a position on the globe, an altitude, sane times and angles
  if (!limits::within(m.z, limits::kPosition_m) || (!(m.x == 0 && m.y == 0) && !limits::valid_lat_lon(lat, lon)) ||
      !params_in_range(m)) {
    *error = kMissionError;
    return std::nullopt;
  }
  const double home_up = fc.home_set() ? fc.home_enu_m().z() : 0.0;
  const double up = amsl ? m.z - config_.origin.alt_m : home_up + m.z;
  item.position_valid = !(m.x == 0 && m.y == 0);
  if (item.position_valid) {
    const Eigen::Vector3d p = enu_of_geodetic({lat, lon, config_.origin.alt_m});
    item.position_enu_m = {p.x(), p.y(), up};
  } else {
    item.position_enu_m = {0.0, 0.0, up};
  }
  switch (static_cast<MavCmd>(m.command)) {
    case MavCmd::NavWaypoint:  // param1 = hold time
      item.kind = fc::MissionItem::Kind::kWaypoint;
      item.param_s_or_m_s = m.param1;
      break;
    case MavCmd::NavTakeoff:  // altitude above home
      item.kind = fc::MissionItem::Kind::kTakeoff;
      item.position_enu_m.z() = amsl ? m.z - config_.origin.alt_m - home_up : m.z;
      break;
    case MavCmd::NavLand:
      item.kind = fc::MissionItem::Kind::kLand;
      break;
    case MavCmd::NavReturnToLaunch:
      item.kind = fc::MissionItem::Kind::kRtl;
      item.position_valid = false;
      break;
    case MavCmd::NavLoiterTime:  // param1 = seconds
      item.kind = fc::MissionItem::Kind::kLoiterTime;
      item.param_s_or_m_s = m.param1;
      break;
    case MavCmd::DoChangeSpeed:  // param2 = speed
      item.kind = fc::MissionItem::Kind::kChangeSpeed;
      item.param_s_or_m_s = m.param2;
      item.position_valid = false;
      break;
    case MavCmd::ConditionYaw:  // param1 = angle
      item.kind = fc::MissionItem::Kind::kConditionYaw;
      item.yaw_enu_rad = yaw_enu_rad_from_heading_deg(m.param1);
      item.position_valid = false;
      break;
    default:
      *error = kMissionUnsupported;
      return std::nullopt;
  }
  if (!item.position_enu_m.allFinite() || !std::isfinite(item.param_s_or_m_s) || !std::isfinite(item.yaw_enu_rad)) {
    *error = kMissionError;
    return std::nullopt;
  }
  return item;
}

msg::MissionItemInt VehicleLink::mission_item_to_mavlink(const fc::MissionItem& item, int seq) const {
  const fc::FlightController& fc = sim_.fc(vehicle_);
  const double home_up = fc.home_set() ? fc.home_enu_m().z() : 0.0;
  msg::MissionItemInt m;
  m.seq = static_cast<std::uint16_t>(seq);
  m.frame = mav_frame(MavFrame::GlobalRelativeAltInt);
  m.autocontinue = 1;
  m.current = (seq == fc.mission_current()) ? 1 : 0;
  if (item.position_valid) {
    const Geodetic g = geodetic_of_enu(item.position_enu_m);
    m.x = static_cast<std::int32_t>(std::llround(g.lat_deg * 1e7));
    m.y = static_cast<std::int32_t>(std::llround(g.lon_deg * 1e7));
  }
  m.z = static_cast<float>(item.position_enu_m.z() - home_up);
  switch (item.kind) {
    case fc::MissionItem::Kind::kWaypoint:
      m.command = mav_command(MavCmd::NavWaypoint);
      m.param1 = static_cast<float>(item.param_s_or_m_s);
      break;
    case fc::MissionItem::Kind::kTakeoff:
      m.command = mav_command(MavCmd::NavTakeoff);
      m.z = static_cast<float>(item.position_enu_m.z());
      break;
    case fc::MissionItem::Kind::kLand: m.command = mav_command(MavCmd::NavLand); break;
    case fc::MissionItem::Kind::kRtl: m.command = mav_command(MavCmd::NavReturnToLaunch); break;
    case fc::MissionItem::Kind::kLoiterTime:
      m.command = mav_command(MavCmd::NavLoiterTime);
      m.param1 = static_cast<float>(item.param_s_or_m_s);
      break;
    case fc::MissionItem::Kind::kChangeSpeed:
      m.command = mav_command(MavCmd::DoChangeSpeed);
      m.param1 = static_cast<float>(to_underlying(SpeedType::Groundspeed));
      m.param2 = static_cast<float>(item.param_s_or_m_s);
      m.param3 = -1;
      break;
    case fc::MissionItem::Kind::kConditionYaw:
      m.command = mav_command(MavCmd::ConditionYaw);
      m.param1 = static_cast<float>(heading_deg_from_yaw_enu_rad(item.yaw_enu_rad));
      break;
  }
  if (seq == 0) {  // home: absolute altitude, frame GLOBAL, as ArduPilot sends it
    m.frame = mav_frame(MavFrame::Global);
    m.command = mav_command(MavCmd::NavWaypoint);
    m.z = static_cast<float>(config_.origin.alt_m + item.position_enu_m.z());
  }
  return m;
}

void VehicleLink::guided_goto(Link& link, const Frame& f, const msg::MissionItemInt& m, bool is_int,
                              fc::FlightController& fc) {
  std::uint8_t error = kMissionError;
  msg::MissionItemInt item = m;
  item.command = mav_command(MavCmd::NavWaypoint);
  auto target_item = mission_item_from_mavlink(item, is_int, &error);
  if (!target_item || fc.mode() != fc::Mode::kGuided) {
    send_mission_ack(link, f.sysid, f.compid, target_item ? kMissionError : error);
    return;
  }
  fc::GuidedTarget t;
  Eigen::Vector3d p = target_item->position_enu_m;
  if (m.current == 3 || !target_item->position_valid) {  // altitude change only: keep the horizontal target
    const auto current = fc.current_target();
    const Eigen::Vector3d keep =
        current && current->position_enu_m ? *current->position_enu_m : fc.estimate().position_enu_m;
    p.x() = keep.x();
    p.y() = keep.y();
  }
  t.position_enu_m = p;
  const fc::CommandResult r = fc.set_guided_target(t);
  send_mission_ack(link, f.sysid, f.compid, r == fc::CommandResult::kAccepted ? kMissionAccepted : kMissionError);
}

void VehicleLink::reject_mission_item(Link& link, const Frame& f) {
  apply_upload_step(link, link.upload.on_unreadable_item(), f.sysid, f.compid);
}

void VehicleLink::handle_mission_item(Link& link, const Frame& f, const msg::MissionItemInt& m, bool is_int,
                                      fc::FlightController& fc) {
  if (m.current == 2 || m.current == 3) {  // guided goto / altitude change (DroneKit simple_goto)
    guided_goto(link, f, m, is_int, fc);
    return;
  }
  const auto read = [&](int seq) -> MissionUpload::ReadItem {
    if (seq == 0) {
      // item 0 is home: the vehicle keeps its own home, the slot is a placeholder
      fc::MissionItem home;
      home.kind = fc::MissionItem::Kind::kWaypoint;
      home.position_enu_m = fc.home_enu_m();
      return home;
    }
    std::uint8_t error = kMissionError;
    auto converted = mission_item_from_mavlink(m, is_int, &error);
    if (!converted) return error;
    return *converted;
  };
  apply_upload_step(link, link.upload.on_item(m.seq, m.mission_type, now_s(), read), f.sysid, f.compid);
}

void VehicleLink::handle_mission_item_float(Link& link, const Frame& f, const msg::MissionItem& m,
                                            fc::FlightController& fc) {
  // carried in the INT struct (1 cm resolution); a latitude/longitude out of range would overflow
  // that conversion, so it is refused
  const auto i = mission_item_int_from_legacy(m);
  if (!i) {
    StatCounters::add(stats_.rejected_inputs);
    reject_mission_item(link, f);
    return;
  }
  handle_mission_item(link, f, *i, false, fc);
}

void VehicleLink::handle_mission_request_list(Link& link, const Frame& f, int mission_type,
                                              fc::FlightController& fc) {
  msg::MissionCount c;
  c.target_system = f.sysid;
  c.target_component = f.compid;
  c.mission_type = static_cast<std::uint8_t>(mission_type);
  c.count = mission_type == kMissionTypeMission
                ? static_cast<std::uint16_t>(std::max<std::size_t>(fc.mission().size(), 1))
                : 0;
  send(link, c);
}

void VehicleLink::handle_mission_request(Link& link, const Frame& f, int seq, bool want_int,
                                         fc::FlightController& fc) {
  const auto& mission = fc.mission();
  msg::MissionItemInt m;
  if (seq == 0 && mission.empty()) {
    fc::MissionItem home;
    home.position_enu_m = fc.home_enu_m();
    m = mission_item_to_mavlink(home, 0);
  } else if (seq >= 0 && static_cast<std::size_t>(seq) < mission.size()) {
    m = mission_item_to_mavlink(mission[seq], seq);
  } else {
    StatCounters::add(stats_.rejected_inputs);
    send_mission_ack(link, f.sysid, f.compid, kMissionInvalidSequence);
    return;
  }
  m.target_system = f.sysid;
  m.target_component = f.compid;
  if (want_int) {
    send(link, m);
    return;
  }
  send(link, legacy_mission_item(m));
}

void VehicleLink::handle_mission_clear_all(Link& link, const Frame& f, int mission_type,
                                           fc::FlightController& fc) {
  if (!is_one_of<MavMissionType>(mission_type, {MavMissionType::Mission, MavMissionType::All})) {
    send_mission_ack(link, f.sysid, f.compid, kMissionUnsupported, static_cast<std::uint8_t>(mission_type));
    return;
  }
  // an upload in progress (any client's) would set its mission after the clear: the clear is DENIED
  // and the upload goes on (it used to be ACCEPTED, then overwritten)
  if (link.upload.active() || upload_by_another_link(link)) {
    StatCounters::add(stats_.rejected_inputs);
    send_mission_ack(link, f.sysid, f.compid, kMissionDenied, static_cast<std::uint8_t>(mission_type));
    return;
  }
  fc.set_mission({});
  send_mission_ack(link, f.sysid, f.compid, kMissionAccepted, static_cast<std::uint8_t>(mission_type));
}

void VehicleLink::handle_mission_set_current(int seq, fc::FlightController& fc) {
  if (fc.set_mission_current(seq) != fc::CommandResult::kAccepted) StatCounters::add(stats_.rejected_inputs);
  // echo with MISSION_CURRENT (no ack), whether or not it changed
  broadcast(mission_current());
}

}  // namespace uavsim::server::mavlink
