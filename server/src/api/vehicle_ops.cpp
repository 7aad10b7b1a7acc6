#include "api/vehicle_ops.hpp"

#include <cmath>
#include <string>
#include <vector>

#include "api/request_fields.hpp"
#include "api/vehicle_arg.hpp"
#include "sim/checked_number.hpp"
#include "uavsim/common/angles.hpp"

namespace uavsim::server::api {

namespace {

using Json = nlohmann::json;

constexpr double kMaxGlitch_m = 1e5;
constexpr double kMaxGimbalAngle_deg = 360.0;

Json vec3(const Eigen::Vector3d& v) { return Json::array({v.x(), v.y(), v.z()}); }

}  // namespace

void VehicleOps::register_ops(OpTable& table) {
  using Fault = void (VehicleOps::*)(size_t, const Json&, OpReply*);
  const OpRegistrar<VehicleOps> query(table, this, "vehicle");
  // a fault names a vehicle and answers it with the sim time it took effect
  const auto fault = [&](const char* name, Fault op) {
    table.add({name, "fault",
               [this, op](uint64_t, const Json& request, OpReply* reply) {
                 const std::optional<size_t> v = required_vehicle(sim_, request, reply);
                 if (!v) return;
                 (this->*op)(*v, request, reply);
                 if (!reply->failed()) reply->result = {{"vehicle", *v}, {"time_s", sim_.time_s()}};
               },
               core_op_fields()});
  };
  query("vehicles", &VehicleOps::vehicles);
  query("truck", &VehicleOps::truck);
  query("balloons", &VehicleOps::balloons);
  fault("kill_vehicle", &VehicleOps::kill_vehicle);
  fault("motor_failure", &VehicleOps::motor_failure);
  fault("gps_glitch", &VehicleOps::gps_glitch);
  fault("gps_denied", &VehicleOps::gps_denied);
  fault("link_drop", &VehicleOps::link_drop);
  query("gimbal", &VehicleOps::gimbal);
  query("wind", &VehicleOps::wind);
}

// ---------------------------------------------------------------------------------------------------
// ground truth

Json VehicleOps::vehicle_json(size_t i) {
  const fc::TruthState t = sim_.truth(i);
  const sim::VehicleRuntime& rt = sim_.runtime(i);
  Json failed = Json::array();
  for (size_t k = 0; k < rt.motors.failed.size(); ++k) {
    if (rt.motors.failed[k]) failed.push_back(k);
  }
  return Json{
      {"index", i},
      {"name", sim_.vehicle_name(i)},
      {"frame", sim_.airframe(i).frame},
      {"position_enu_m", vec3(t.position_enu_m)},
      {"velocity_enu_m_s", vec3(t.velocity_enu_m_s)},
      {"q_enu_body", {t.q_enu_body.w(), t.q_enu_body.x(), t.q_enu_body.y(), t.q_enu_body.z()}},
      {"rate_body_rad_s", vec3(t.rate_body_rad_s)},
      {"armed", sim_.fc(i).armed()},
      {"mode", fc::mode_name(sim_.fc(i).mode())},
      {"crashed", rt.crashed},
      {"on_ground", rt.on_ground},
      {"battery_v", rt.battery.voltage_v},
      {"battery_used_mah", rt.battery.consumed_mah},
      {"failed_motors", failed}};
}

void VehicleOps::vehicles(const Json&, OpReply* reply) {
  Json list = Json::array();
  for (size_t i = 0; i < sim_.vehicle_count(); ++i) list.push_back(vehicle_json(i));
  reply->result = {{"time_s", sim_.time_s()}, {"vehicles", list}};
}

void VehicleOps::truck(const Json&, OpReply* reply) {
  if (objects_.trucks.empty())
    return reply->fail(ApiError::kNotAvailable, "this world has no truck");
  Json trucks = Json::array();
  for (const objects::Truck* truck : objects_.trucks) {
    const objects::TruckState s = truck->state(sim_.time_s());
    trucks.push_back({{"name", s.name},
                      {"position_enu_m", vec3(s.position_enu_m)},
                      {"velocity_enu_m_s", vec3(s.velocity_enu_m_s)},
                      {"yaw_rad", s.yaw_rad},
                      {"speed_m_s", s.speed_m_s},
                      {"s_m", s.s_m},
                      {"laps", s.laps},
                      {"track_length_m", truck->track().length_m()},
                      {"deck_centre_enu_m", vec3(s.deck_centre_enu_m)},
                      {"carried_vehicles", s.carried_vehicles}});
  }
  reply->result = {{"time_s", sim_.time_s()}, {"trucks", trucks}};
}

void VehicleOps::balloons(const Json&, OpReply* reply) {
  if (objects_.balloons == nullptr)
    return reply->fail(ApiError::kNotAvailable, "this world has no balloons");
  Json balloons = Json::array();
  for (const objects::BalloonState& b : objects_.balloons->balloons()) {
    balloons.push_back({{"name", b.name},
                        {"position_enu_m", vec3(b.position_enu_m)},
                        {"radius_m", b.radius_m},
                        {"popped", b.popped},
                        {"popped_by", b.popped ? Json(b.popped_by) : Json(nullptr)},
                        {"popped_time_s", b.popped ? Json(b.popped_time_s) : Json(nullptr)}});
  }
  reply->result = {{"time_s", sim_.time_s()}, {"balloons", balloons}};
}

// ---------------------------------------------------------------------------------------------------
// fault injection

void VehicleOps::kill_vehicle(size_t v, const Json& request, OpReply*) {
  const std::string reason = string_field(request, "reason").value_or("fault injection");
  sim_.record(sim::EventType::kVehicleKilled, static_cast<int>(v), reason);
  sim_.kill_vehicle(v, "killed: " + reason);
}

void VehicleOps::motor_failure(size_t v, const Json& request, OpReply* reply) {
  const auto rotor = number_field(request, "rotor");
  const size_t rotors = sim_.airframe(v).rotors.size();
  if (!rotor) return reply->fail(ApiError::kMissingField, "\"rotor\" (index) is required");
  if (*rotor < 0 || *rotor >= static_cast<double>(rotors) || std::floor(*rotor) != *rotor) {
    return reply->fail(ApiError::kBadField,
                       "\"rotor\" must be in [0, " + std::to_string(rotors) + ")");
  }
  sim_.set_motor_failed(v, static_cast<size_t>(*rotor),
                        bool_field(request, "failed").value_or(true));
}

void VehicleOps::gps_glitch(size_t v, const Json& request, OpReply* reply) {
  auto it = request.find("offset_enu_m");
  if (it == request.end()) {
    return reply->fail(ApiError::kMissingField,
                       "\"offset_enu_m\" [x, y, z] is required ([0, 0, 0] clears the glitch)");
  }
  const auto in_range = [](const Json& x) {
    return x.is_number() && std::abs(x.get<double>()) <= kMaxGlitch_m;
  };
  if (it->size() != 3 || !in_range((*it)[0]) || !in_range((*it)[1]) || !in_range((*it)[2])) {
    return reply->fail(ApiError::kBadField,
                       "\"offset_enu_m\" must be three numbers of at most 1e5 m");
  }
  sim_.fc(v).set_gps_glitch(
      Eigen::Vector3d((*it)[0].get<double>(), (*it)[1].get<double>(), (*it)[2].get<double>()));
}

void VehicleOps::gps_denied(size_t v, const Json& request, OpReply*) {
  sim_.fc(v).set_gps_denied(bool_field(request, "denied").value_or(true));
}

void VehicleOps::link_drop(size_t v, const Json& request, OpReply* reply) {
  if (link_ == nullptr)
    return reply->fail(ApiError::kNotAvailable, "no MAVLink endpoint is attached to this server");
  if (!link_->set_link_down(v, bool_field(request, "down").value_or(true))) {
    reply->fail(ApiError::kNotAvailable, "vehicle " + std::to_string(v) + " has no MAVLink link");
  }
}

// ---------------------------------------------------------------------------------------------------
// gimbals and wind

void VehicleOps::gimbal(const Json& request, OpReply* reply) {
  const auto name = string_field(request, "gimbal");
  objects::Gimbal* g = nullptr;
  if (objects_.gimbals != nullptr && name) {
    for (objects::Gimbal& x : objects_.gimbals->gimbals()) {
      if (x.name == *name) g = &x;
    }
  }
  const auto mode = string_field(request, "mode");
  const auto pitch_deg = number_field(request, "pitch_deg");
  const auto yaw_deg = number_field(request, "yaw_deg");
  const auto angle_ok = [](const std::optional<double>& a) {
    return !a || sim::finite_in(*a, -kMaxGimbalAngle_deg, kMaxGimbalAngle_deg);
  };
  if (!name)
    return reply->fail(ApiError::kMissingField, "\"gimbal\" (the gimbal body's name) is required");
  if (g == nullptr) return reply->fail(ApiError::kBadField, "no gimbal named '" + *name + "'");
  if (mode && *mode != "down" && *mode != "forward" && *mode != "targets") {
    return reply->fail(ApiError::kBadField, "\"mode\" must be down, forward or targets");
  }
  if (!angle_ok(pitch_deg) || !angle_ok(yaw_deg)) {
    return reply->fail(ApiError::kBadField, "\"pitch_deg\" and \"yaw_deg\" must be in [-360, 360]");
  }
  if (mode) {
    g->mode = *mode == "down"      ? objects::GimbalMode::kDown
              : *mode == "forward" ? objects::GimbalMode::kForward
                                   : objects::GimbalMode::kTargets;
  }
  if (pitch_deg) g->pitch_rad = *pitch_deg * common::kPi / 180.0;
  if (yaw_deg) g->yaw_rad = *yaw_deg * common::kPi / 180.0;
  reply->result = {{"gimbal", g->name},
                   {"mode", objects::gimbal_mode_name(g->mode)},
                   {"pitch_deg", g->pitch_rad * 180.0 / common::kPi},
                   {"yaw_deg", g->yaw_rad * 180.0 / common::kPi}};
}

void VehicleOps::wind(const Json& request, OpReply* reply) {
  // set what is given (speed, direction, turbulence), start a gust if asked; answer the wind now
  airframe::WindParams w = sim_.wind().params();
  const auto speed = number_field(request, "speed_m_s");
  const auto from = number_field(request, "from_deg");
  const auto turbulence = number_field(request, "turbulence_sd_m_s");
  const auto gust = number_field(request, "gust_m_s");
  const auto gust_duration = number_field(request, "gust_duration_s");
  if (speed) w.speed_m_s = *speed;
  if (from) w.from_deg = *from;
  if (turbulence) w.turbulence_sd_m_s = *turbulence;
  const std::string why = airframe::validate(w);
  if (!why.empty() || (from && std::abs(*from) > 360.0)) {
    return reply->fail(ApiError::kBadField,
                       why.empty() ? "\"from_deg\" must be in [-360, 360]" : why);
  }
  if ((gust && !sim::finite_in(*gust, 0.0, 50.0)) ||
      (gust_duration && !sim::finite_in(*gust_duration, 0.01, 600.0))) {
    return reply->fail(ApiError::kBadField,
                       "\"gust_m_s\" must be in [0, 50] and \"gust_duration_s\" in [0.01, 600]");
  }
  if (speed || from || turbulence) sim_.wind().set_params(w);
  if (gust) sim_.wind().gust(*gust, gust_duration.value_or(w.gust_duration_s));
  const airframe::WindField& f = sim_.wind();
  reply->result = {{"speed_m_s", f.params().speed_m_s},
                   {"from_deg", f.params().from_deg},
                   {"turbulence_sd_m_s", f.params().turbulence_sd_m_s},
                   {"length_scale_m", f.params().length_scale_m},
                   {"gust_m_s", f.gust_m_s()},
                   {"velocity_enu_m_s", vec3(f.velocity_enu_m_s())},
                   {"realism", sim::realism_name(sim_.config().field.realism)},
                   {"time_s", sim_.time_s()}};
}

}  // namespace uavsim::server::api
