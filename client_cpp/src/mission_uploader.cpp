// The mission upload: the items as MISSION_ITEM_INT, a MISSION_COUNT re-sent while the vehicle is
// silent, each requested item answered in the form it was asked for, and the MISSION_ACK's verdict.
#include "mission_uploader.hpp"

#include <algorithm>
#include <string>

#include "mav_units.hpp"
#include "uavsim/common/mavlink/generated/enum_names.hpp"
#include "uavsim/common/mavlink/generated/enums.hpp"
#include "uavsim/common/mavlink/mission_item.hpp"

namespace uavsim::client {

namespace mav = common::mavlink;
namespace msg = common::mavlink::msg;
using mav::MavMissionResult;
using mav::to_underlying;

namespace {

constexpr int kCountAttempts = 3;
// MISSION_COUNT is sent again when no item was requested within this (loop clock)
constexpr double kCountResendS = 1.5;
constexpr std::uint8_t kMissionTypeMission = to_underlying(mav::MavMissionType::Mission);

constexpr std::uint16_t command_id(mav::MavCmd c) {
  return static_cast<std::uint16_t>(to_underlying(c));
}

msg::MissionItemInt to_wire(const MissionItem& it, std::uint16_t seq, const MavPort& port) {
  msg::MissionItemInt m;
  m.target_system = port.target_sysid();
  m.target_component = port.target_compid();
  m.seq = seq;
  m.frame = it.frame;
  m.command = it.command;
  m.autocontinue = it.autocontinue ? 1 : 0;
  m.param1 = it.param1, m.param2 = it.param2, m.param3 = it.param3, m.param4 = it.param4;
  m.x = deg_e7(it.lat_deg);
  m.y = deg_e7(it.lon_deg);
  m.z = it.alt_m;
  m.mission_type = kMissionTypeMission;
  return m;
}

}  // namespace

// MissionItem (vehicle.hpp): the items a mission is made of

MissionItem MissionItem::takeoff(double rel_alt_m) {
  MissionItem m;
  m.command = command_id(mav::MavCmd::NavTakeoff);
  m.alt_m = static_cast<float>(rel_alt_m);
  return m;
}
MissionItem MissionItem::waypoint(double lat_deg, double lon_deg, double rel_alt_m, double hold_s) {
  MissionItem m;
  m.command = command_id(mav::MavCmd::NavWaypoint);
  m.param1 = static_cast<float>(hold_s);
  m.lat_deg = lat_deg;
  m.lon_deg = lon_deg;
  m.alt_m = static_cast<float>(rel_alt_m);
  return m;
}
MissionItem MissionItem::land() {
  MissionItem m;
  m.command = command_id(mav::MavCmd::NavLand);
  return m;
}
MissionItem MissionItem::rtl() {
  MissionItem m;
  m.command = command_id(mav::MavCmd::NavReturnToLaunch);
  return m;
}

MissionUploader::MissionUploader(EventLoop& loop, MavPort& port) : loop_(loop), port_(port) {
  const auto request = [this](const mav::Frame& f) { on_request(f); };
  port_.on_message(msg::MissionRequestInt::kId, request);
  port_.on_message(msg::MissionRequest::kId, request);
  port_.on_message(msg::MissionAck::kId, [this](const mav::Frame& f) { on_ack(f); });
}

Result<void> MissionUploader::upload(const std::vector<MissionItem>& items, const Geodetic& home,
                                     double timeout_s) {
  loop_.assert_in_loop_thread();
  if (auto r = port_.need_open(); !r) return r;
  if (items.empty()) return Result<void>::fail(Error::kInvalidArgument, "an empty mission");
  items_.clear();
  MissionItem home_item;  // item 0: home (ArduPilot overwrites it with the real home)
  home_item.frame = static_cast<std::uint8_t>(to_underlying(mav::MavFrame::Global));
  home_item.lat_deg = home.lat_deg;
  home_item.lon_deg = home.lon_deg;
  home_item.alt_m = static_cast<float>(home.alt_m);
  items_.push_back(to_wire(home_item, 0, port_));
  for (std::size_t i = 0; i < items.size(); ++i) {
    items_.push_back(to_wire(items[i], static_cast<std::uint16_t>(i + 1), port_));
  }
  active_ = true;
  ack_.reset();
  requests_ = 0;

  const double deadline = loop_.now() + timeout_s;
  for (int attempt = 0; attempt < kCountAttempts && loop_.now() < deadline; ++attempt) {
    msg::MissionCount c;
    c.target_system = port_.target_sysid();
    c.target_component = port_.target_compid();
    c.count = static_cast<std::uint16_t>(items_.size());
    c.mission_type = kMissionTypeMission;
    if (!port_.send(c)) break;
    const double sent_at = loop_.now();
    (void)loop_.run_until(
        [&] {
          return ack_.has_value() || !port_.is_open() ||
                 (requests_ == 0 && loop_.now() - sent_at > kCountResendS);
        },
        std::max(0.0, deadline - loop_.now()), "MISSION_ACK");
    if (ack_ || !port_.is_open() || requests_ > 0) break;
  }
  active_ = false;
  return outcome(timeout_s);
}

Result<void> MissionUploader::outcome(double timeout_s) const {
  if (!port_.is_open()) {
    return Result<void>::fail(Error::kConnectionLost, "mission upload: the link was lost");
  }
  if (ack_) {
    const auto r = static_cast<MavMissionResult>(*ack_);
    if (r == MavMissionResult::Accepted) return {};
    const std::string_view name = mav::enum_name(r);
    return Result<void>::fail(
        r == MavMissionResult::OperationCancelled ? Error::kCancelled : Error::kDenied,
        "mission upload refused: MAV_MISSION_" + std::string(name.empty() ? "UNKNOWN" : name) +
            " (" + std::to_string(*ack_) + ")",
        *ack_);
  }
  if (requests_ == 0) {
    return Result<void>::fail(Error::kTimeout,
                              "mission upload: the vehicle never requested an item");
  }
  return Result<void>::fail(
      Error::kTimeout, "mission upload: no MISSION_ACK within " + std::to_string(timeout_s) + " s");
}

// both requests carry (seq, target_system, target_component, mission_type) in the same layout; the
// answer takes the form of the request
void MissionUploader::on_request(const mav::Frame& f) {
  const auto m = msg::MissionRequestInt::decode(f.payload.data());
  if (!active_ || m.mission_type != kMissionTypeMission) return;
  if (m.seq >= items_.size()) return;
  ++requests_;
  if (f.msgid == msg::MissionRequestInt::kId) {
    port_.send(items_[m.seq]);
  } else {
    port_.send(mav::legacy_mission_item(items_[m.seq]));
  }
}

void MissionUploader::on_ack(const mav::Frame& f) {
  const auto m = msg::MissionAck::decode(f.payload.data());
  if (active_ && m.mission_type == kMissionTypeMission) ack_ = m.type;
}

}  // namespace uavsim::client
