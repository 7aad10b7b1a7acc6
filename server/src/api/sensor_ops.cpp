#include "api/sensor_ops.hpp"

#include "api/request_fields.hpp"
#include "api/vehicle_arg.hpp"

namespace uavsim::server::api {

namespace {
constexpr const char* kSwitchesSensor = "switches";
}  // namespace

SensorOps::SensorOps(sim::Simulation& sim)
    : sim_(sim), switches_(physics::vehicle_touch_sensors(sim.world())) {}

void SensorOps::register_ops(OpTable& table) {
  static constexpr FieldSpec kFields[] = {{"vehicle", FieldType::kIndexOrName}};
  // the group checks its own fields: sensor_list reads none
  const OpRegistrar<SensorOps> add(table, this, "sensor", kFields);
  add("sensor_list", &SensorOps::list, {});
  add("sensor_read", &SensorOps::read_now);
  add("sensor_subscribe", &SensorOps::subscribe);
  add("sensor_unsubscribe", &SensorOps::unsubscribe);
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

void SensorOps::list(OpReply* reply) const {
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
  reply->result = {{"sensors", list}};
}

std::optional<size_t> SensorOps::vehicle_with_switches(const Json& request, OpReply* reply) const {
  const std::optional<size_t> vehicle = required_vehicle(sim_, request, reply);
  if (vehicle && switches_[*vehicle].empty()) {
    reply->fail(ApiError::kNotAvailable,
                "vehicle " + sim_.vehicle_name(*vehicle) + " has no switches (touch sensors)");
    return std::nullopt;
  }
  return vehicle;
}

void SensorOps::read_now(const Json& request, OpReply* reply) const {
  if (const auto vehicle = vehicle_with_switches(request, reply)) {
    reply->result = reading_json(*vehicle, read(*vehicle));
  }
}

void SensorOps::subscribe(uint64_t conn, const Json& request, OpReply* reply) {
  const auto vehicle = vehicle_with_switches(request, reply);
  if (!vehicle) return;
  // the current state goes out at the next gate, as the first event
  subscriptions_[conn][*vehicle].clear();
  reply->result = {
      {"vehicle", sim_.vehicle_name(*vehicle)}, {"sensor", kSwitchesSensor}, {"subscribed", true}};
}

void SensorOps::unsubscribe(uint64_t conn, const Json& request, OpReply* reply) {
  // any vehicle may be unsubscribed, switches or not: there is nothing to stop then
  const auto vehicle = required_vehicle(sim_, request, reply);
  if (!vehicle) return;
  bool was = false;
  if (auto it = subscriptions_.find(conn); it != subscriptions_.end()) {
    was = it->second.erase(*vehicle) > 0;
    if (it->second.empty()) subscriptions_.erase(it);
  }
  reply->result = {
      {"vehicle", sim_.vehicle_name(*vehicle)}, {"sensor", kSwitchesSensor}, {"subscribed", was}};
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
