#include "api/sensor_ops.hpp"

#include <functional>

#include "api/vehicle_arg.hpp"

namespace uavsim::server::api {

namespace {
constexpr const char* kSwitchesSensor = "switches";
}  // namespace

SensorOps::SensorOps(sim::Simulation& sim)
    : sim_(sim), switches_(physics::vehicle_touch_sensors(sim.world())) {}

void SensorOps::register_ops(OpTable& table) {
  static constexpr std::string_view kOps[] = {"sensor_list", "sensor_read", "sensor_subscribe",
                                              "sensor_unsubscribe"};
  table.add_named("sensor", kOps, std::bind_front(&SensorOps::handle, this));
}

std::vector<bool> SensorOps::read(size_t vehicle) const {
  std::vector<bool> closed;
  for (const physics::TouchSensor& s : switches_[vehicle]) {
    closed.push_back(physics::touch_force_n(sim_.world(), s) > kSwitchClosedForce_n);
  }
  return closed;
}

SensorOps::Json SensorOps::reading_json(size_t vehicle, const std::vector<bool>& closed) const {
  bool any = false;
  for (bool c : closed) any = any || c;
  return Json{{"vehicle", sim_.vehicle_name(vehicle)},
              {"vehicle_index", vehicle},
              {"sensor", kSwitchesSensor},
              {"time", sim_.time_s()},
              {"closed", closed},
              {"any", any}};
}

bool SensorOps::handle(uint64_t conn, const std::string& op, const Json& request, Json* result,
                       std::string* code, std::string* message) {
  if (op == "sensor_list") {
    Json list = Json::array();
    for (size_t v = 0; v < switches_.size(); ++v) {
      if (switches_[v].empty()) continue;
      Json names = Json::array();
      for (const physics::TouchSensor& s : switches_[v]) names.push_back(s.name);
      list.push_back({{"vehicle", sim_.vehicle_name(v)},
                      {"vehicle_index", v},
                      {"sensor", kSwitchesSensor},
                      {"names", names},
                      {"closed_above_n", kSwitchClosedForce_n}});
    }
    *result = {{"sensors", list}};
    return true;
  }
  auto field = request.find("vehicle");
  if (field == request.end()) {
    *code = "missing_field";
    *message = "\"vehicle\" (an index or a name) is required";
    return false;
  }
  const std::optional<size_t> vehicle = vehicle_index(sim_, *field, code, message);
  if (!vehicle) return false;
  if (switches_[*vehicle].empty() && op != "sensor_unsubscribe") {
    *code = "not_available";
    *message = "vehicle " + sim_.vehicle_name(*vehicle) + " has no switches (touch sensors)";
    return false;
  }
  if (op == "sensor_read") {
    *result = reading_json(*vehicle, read(*vehicle));
  } else if (op == "sensor_subscribe") {
    // the current state goes out at the next gate, as the first event
    subscriptions_[conn][*vehicle].clear();
    *result = {{"vehicle", sim_.vehicle_name(*vehicle)},
               {"sensor", kSwitchesSensor},
               {"subscribed", true}};
  } else {  // sensor_unsubscribe
    bool was = false;
    if (auto it = subscriptions_.find(conn); it != subscriptions_.end()) {
      was = it->second.erase(*vehicle) > 0;
      if (it->second.empty()) subscriptions_.erase(it);
    }
    *result = {
        {"vehicle", sim_.vehicle_name(*vehicle)}, {"sensor", kSwitchesSensor}, {"subscribed", was}};
  }
  return true;
}

void SensorOps::on_gate(const Send& send, const InLockstep& /*in_lockstep*/) {
  if (subscriptions_.empty()) return;
  // one reading per vehicle per gate, sent to each subscriber whose last state differs
  std::map<size_t, std::vector<bool>> now;
  for (auto& [conn, vehicles] : subscriptions_) {
    for (auto& [vehicle, last] : vehicles) {
      auto it = now.find(vehicle);
      if (it == now.end()) it = now.emplace(vehicle, read(vehicle)).first;
      if (it->second == last) continue;
      last = it->second;
      Json event = reading_json(vehicle, last);
      event["event"] = "sensor";
      send(conn, event);
    }
  }
}

void SensorOps::on_disconnect(uint64_t conn) { subscriptions_.erase(conn); }

}  // namespace uavsim::server::api
