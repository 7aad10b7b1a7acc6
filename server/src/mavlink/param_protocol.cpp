// The parameter protocol over the flight controller's live parameter table (docs/mavlink.md §6.1):
// values as float casts with the parameter's own param_type (INT8/INT16/INT32/REAL32, as ArduPilot
// sends them), param_index = the FC's fixed order, unknown names and non-finite values ignored as
// ArduPilot does; an integer parameter keeps the whole part of a value set (1.7 -> 1), whatever
// param_type the setter sent.
#include <cmath>

#include "mavlink/vehicle_link.hpp"

namespace uavsim::server::mavlink {

namespace {

std::uint8_t mav_param_type(fc::ParamKind kind) {
  MavParamType t = MavParamType::Real32;
  switch (kind) {
    case fc::ParamKind::kFloat: t = MavParamType::Real32; break;
    case fc::ParamKind::kInt8: t = MavParamType::Int8; break;
    case fc::ParamKind::kInt16: t = MavParamType::Int16; break;
    case fc::ParamKind::kInt32: t = MavParamType::Int32; break;
  }
  return static_cast<std::uint8_t>(to_underlying(t));
}

// PARAM_VALUE of the named parameter at param_index (65535 for the echo of a set)
msg::ParamValue param_value(const fc::FlightController& fc, const std::string& name, std::uint16_t index) {
  msg::ParamValue v;
  set_string(v.param_id, name);
  v.param_value = static_cast<float>(fc.param(name).value_or(0.0));
  v.param_type = mav_param_type(fc.param_kind(name).value_or(fc::ParamKind::kFloat));
  v.param_count = static_cast<std::uint16_t>(fc.param_names().size());
  v.param_index = index;
  return v;
}

}  // namespace

void VehicleLink::send_param(Link& link, std::size_t index) {
  const fc::FlightController& fc = sim_.fc(vehicle_);
  const auto& names = fc.param_names();
  if (index >= names.size()) return;
  send(link, param_value(fc, names[index], static_cast<std::uint16_t>(index)));
}

void VehicleLink::handle_param_request_list(Link& link) {
  // banner first, as ArduPilot does, then the whole table paced over the next control steps
  send_status_text(to_underlying(MavSeverity::Info), "ArduCopter V4.5.0 (uavsim)");
  send_status_text(to_underlying(MavSeverity::Info),
                   mav_type_ == to_underlying(MavType::Hexarotor) ? "Frame: HEXA" : "Frame: QUAD");
  link.params.start();
}

void VehicleLink::service_param_download(Link& link) {
  link.params.take(sim_.fc(vehicle_).param_names().size(), [&](std::size_t i) { send_param(link, i); });
}

void VehicleLink::handle_param_request_read(Link& link, const msg::ParamRequestRead& m) {
  const auto& names = sim_.fc(vehicle_).param_names();
  if (m.param_index >= 0) {
    if (static_cast<std::size_t>(m.param_index) < names.size()) {
      send_param(link, static_cast<std::size_t>(m.param_index));
    } else {
      StatCounters::add(stats_.rejected_inputs);
    }
    return;
  }
  if (const auto index = param_index(names, get_string(m.param_id))) {
    send_param(link, *index);
    return;
  }
  StatCounters::add(stats_.rejected_inputs);  // unknown name: no reply, as ArduPilot
}

void VehicleLink::handle_param_set(const msg::ParamSet& m, fc::FlightController& fc) {
  const std::string name(get_string(m.param_id));
  const auto& names = fc.param_names();
  if (!param_index(names, name) || !std::isfinite(m.param_value)) {
    StatCounters::add(stats_.rejected_inputs);  // ignored silently, as ArduPilot
    return;
  }
  if (fc.set_param(name, m.param_value) != fc::CommandResult::kAccepted) {
    StatCounters::add(stats_.rejected_inputs);  // out of range: the echo below reports the unchanged value
  }
  if (name == "SYSID_THISMAV") {
    if (const auto id = fc.param(name)) sysid_ = static_cast<std::uint8_t>(*id);
  }
  // the echo goes to every client, with param_index 65535 as ArduPilot's send_parameter_value
  broadcast(param_value(fc, name, 65535));
}

}  // namespace uavsim::server::mavlink
