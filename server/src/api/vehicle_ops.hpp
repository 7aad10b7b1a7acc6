// The API's ground-truth queries and world manipulation (docs/protocol.md "World queries", "Fault
// injection", "Gimbals", "Wind"): vehicles, truck, balloons, kill_vehicle, motor_failure,
// gps_glitch, gps_denied, link_drop, gimbal, wind. An op group; every op runs on the loop thread.
#pragma once

#include <cstddef>
#include <nlohmann/json.hpp>
#include <optional>

#include "api/op_table.hpp"
#include "objects/world_objects.hpp"
#include "sim/simulation.hpp"

namespace uavsim::server::api {

// Implemented by the MAVLink endpoint: cut or restore a vehicle's MAVLink link (fault injection).
class LinkControl {
 public:
  virtual ~LinkControl() = default;
  // Drops (down = true) or restores a vehicle's link: while down, nothing is delivered either way.
  // Thread-safe. False if the vehicle has no link.
  virtual bool set_link_down(size_t vehicle, bool down) = 0;
};

class VehicleOps : public OpGroup {
 public:
  // sim must outlive this object. Before the server starts.
  VehicleOps(sim::Simulation& sim, objects::ObjectSet objects)
      : sim_(sim), objects_(std::move(objects)) {}

  // The endpoint that link_drop acts on (null: link_drop answers not_available). Before the server
  // starts.
  void set_link_control(LinkControl* link) { link_ = link; }

  void register_ops(OpTable& table) override;

 private:
  // one per op: (conn, request) => reply
  void vehicles(const Json& request, OpReply* reply);
  void truck(const Json& request, OpReply* reply);
  void balloons(const Json& request, OpReply* reply);
  void kill_vehicle(size_t vehicle, const Json& request, OpReply* reply);
  void motor_failure(size_t vehicle, const Json& request, OpReply* reply);
  void gps_glitch(size_t vehicle, const Json& request, OpReply* reply);
  void gps_denied(size_t vehicle, const Json& request, OpReply* reply);
  void link_drop(size_t vehicle, const Json& request, OpReply* reply);
  void gimbal(const Json& request, OpReply* reply);
  void wind(const Json& request, OpReply* reply);
  Json vehicle_json(size_t i);

  sim::Simulation& sim_;
  objects::ObjectSet objects_;
  LinkControl* link_ = nullptr;
};

}  // namespace uavsim::server::api
