// Onboard sensors on the sim socket API (docs/protocol.md "Onboard sensors"): what a vehicle's own
// computer reads from its hardware, served to that vehicle's program like its camera — never ground
// truth. Today: the landing-pad microswitches (MuJoCo touch sensors on the pad sites of
// models/vehicles/hexa.xml, seed 7.1 fig. 7.2), one boolean per pad, closed while the pad presses
// on something with more than kSwitchClosedForce_n.
//
// Ops: sensor_list, sensor_read (one reading now), sensor_subscribe / sensor_unsubscribe (a
// {"event": "sensor", ...} message at every change of a vehicle's switches, and one at
// subscribing). Changes stream at the gate, before ticks are announced, so a lockstep client
// receives the switch state of sim time t before tick t — as an interrupt on a GPIO line reaches a
// flight computer.
#pragma once

#include <cstdint>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "api/op_table.hpp"
#include "physics/touch_sensors.hpp"
#include "sim/simulation.hpp"

namespace uavsim::server::api {

// A microswitch closes above this normal force: a fraction of a 6.8 kg hexa's weight on one pad
// (16.7 N), well above contact noise while airborne (none) and below a touchdown's first contact.
inline constexpr double kSwitchClosedForce_n = 1.0;

class SensorOps : public OpGroup {
 public:
  // Finds every vehicle's touch sensors in sim's world. sim must outlive this object. Before the
  // loop.
  explicit SensorOps(sim::Simulation& sim);

  // sensor_list, sensor_read, sensor_subscribe, sensor_unsubscribe.
  void register_ops(OpTable& table) override;
  void on_gate(const Send& send, const InLockstep& in_lockstep) override;
  void on_disconnect(uint64_t conn) override;

 private:
  // the switch states of a vehicle now
  std::vector<bool> read(size_t vehicle) const;
  Json reading_json(size_t vehicle, const std::vector<bool>& closed) const;
  // the ops (loop thread)
  void list(OpReply* reply) const;
  void read_now(const Json& request, OpReply* reply) const;
  void subscribe(uint64_t conn, const Json& request, OpReply* reply);
  void unsubscribe(uint64_t conn, const Json& request, OpReply* reply);
  // the request's vehicle, which must have switches
  std::optional<size_t> vehicle_with_switches(const Json& request, OpReply* reply) const;

  sim::Simulation& sim_;
  std::vector<std::vector<physics::TouchSensor>> switches_;  // per vehicle
  // conn -> vehicle -> the state last sent (empty: nothing sent yet)
  std::map<uint64_t, std::map<size_t, std::vector<bool>>> subscriptions_;
};

}  // namespace uavsim::server::api
