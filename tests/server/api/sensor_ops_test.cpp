// The landing-pad microswitches (sensor_ops.hpp): MuJoCo touch sensors on the hexa's pad sites,
// read as switches through the API's sensor ops, on the ground, in the air and on the moving
// truck's deck.
#include "api/sensor_ops.hpp"

#include <gtest/gtest.h>

#include <fstream>
#include <memory>
#include <string>
#include <vector>

#include "objects/world_objects.hpp"
#include "physics/object_bodies.hpp"
#include "physics/world.hpp"
#include "call_op.hpp"

namespace uavsim::server::api {
namespace {

using Json = nlohmann::json;

// skids: capsules 0.35 m below the hexa's origin, radius 0.012 m
constexpr double kSkidDepth_m = 0.35 + 0.012;

std::unique_ptr<sim::Simulation> hexa_and_truck(const std::string& label) {
  const std::string path = ::testing::TempDir() + "/uavsim_sensor_" + label + ".xml";
  std::ofstream(path)
      << "<mujoco model=\"" << label << "\">\n"
      << "  <compiler angle=\"radian\"/>\n"
      << "  <option timestep=\"0.001\" integrator=\"Euler\"/>\n"
      << "  <include file=\"" << UAVSIM_MODELS_DIR << "/common/ground.xml\"/>\n"
      << "  <worldbody>\n"
      << "    <uavsim_object type=\"truck\" name=\"truck\"/>\n"
      << "    <uavsim_vehicle type=\"hexa\" name=\"uav0\" pos=\"-30 -20 0\"/>\n"
      << "  </worldbody>\n"
      << "  <custom><numeric name=\"uavsim:truck:speed\" data=\"15 5 480 0\"/></custom>\n"
      << "</mujoco>\n";
  physics::ComposeOptions o;
  o.models_dir = UAVSIM_MODELS_DIR;
  return std::make_unique<sim::Simulation>(physics::World::load(path, o), sim::SimConfig{});
}

Json call(SensorOps& ops, const std::string& op, const Json& request, uint64_t conn = 1) {
  return testing::call_op(ops, op, request, conn);
}

std::vector<Json> gate(SensorOps& ops) {
  std::vector<Json> sent;
  ops.on_gate([&](uint64_t, const Json& m) { sent.push_back(m); }, [](uint64_t) { return false; });
  return sent;
}

TEST(PadSwitches, TheHexaHasFourPadSwitchesClosedOnTheGroundOpenInTheAir) {
  auto sim = hexa_and_truck("ground_air");
  (void)objects::add_world_objects(*sim);
  SensorOps ops(*sim);
  const Json list = call(ops, "sensor_list", {});
  ASSERT_EQ(list["sensors"].size(), 1u);
  EXPECT_EQ(list["sensors"][0]["vehicle"], "uav0");
  EXPECT_EQ(list["sensors"][0]["names"], Json({"pad0", "pad1", "pad2", "pad3"}));

  // standing on its skids: the weight (6.8 kg x 9.81 = 66.7 N) rests on the four pads
  sim->run_until(0.5);
  Json r = call(ops, "sensor_read", {{"vehicle", "uav0"}});
  EXPECT_EQ(r["closed"], Json({true, true, true, true}));
  EXPECT_TRUE(r["any"].get<bool>());

  // subscribing sends the state once, then only changes
  EXPECT_TRUE(call(ops, "sensor_subscribe", {{"vehicle", 0}})["subscribed"].get<bool>());
  std::vector<Json> sent = gate(ops);
  ASSERT_EQ(sent.size(), 1u);
  EXPECT_EQ(sent[0]["event"], "sensor");
  EXPECT_TRUE(sent[0]["any"].get<bool>());
  sim->run_until(0.6);
  EXPECT_TRUE(gate(ops).empty());

  // lifted 2 m: every switch opens
  physics::set_vehicle_state(sim->world(), 0, Eigen::Vector3d(-30, -20, 2.0),
                             Eigen::Quaterniond::Identity(), Eigen::Vector3d::Zero(),
                             Eigen::Vector3d::Zero());
  sim->step();
  sent = gate(ops);
  ASSERT_EQ(sent.size(), 1u);
  EXPECT_EQ(sent[0]["closed"], Json({false, false, false, false}));
  EXPECT_FALSE(sent[0]["any"].get<bool>());

  EXPECT_FALSE(call(ops, "sensor_unsubscribe", {{"vehicle", "uav0"}}).contains("error"));
  sim->run_until(1.5);  // fell back down: no event after unsubscribing
  EXPECT_TRUE(gate(ops).empty());
}

TEST(PadSwitches, BadRequestsAreErrors) {
  auto sim = hexa_and_truck("bad");
  SensorOps ops(*sim);
  EXPECT_EQ(call(ops, "sensor_read", {})["error"], "missing_field");
  EXPECT_EQ(call(ops, "sensor_read", {{"vehicle", 3}})["error"], "unknown_vehicle");
  EXPECT_EQ(call(ops, "sensor_read", {{"vehicle", -1}})["error"], "unknown_vehicle");
  EXPECT_EQ(call(ops, "sensor_subscribe", {{"vehicle", "uav9"}})["error"], "unknown_vehicle");
  EXPECT_EQ(call(ops, "sensor_subscribe", {{"vehicle", Json::array()}})["error"], "bad_field");
}

// The seed's landing (7.1): a pad switch closes on the moving deck, the motors are cut at once
// (force disarm, as MAV_CMD_COMPONENT_ARM_DISARM with 21196 does), and the truck carries the hexa.
TEST(PadSwitches, ForceDisarmedOnTheMovingDeckTheHexaRidesAlong) {
  auto sim = hexa_and_truck("deck");
  const objects::ObjectSet set = objects::add_world_objects(*sim);
  const objects::Truck& truck = *set.trucks[0];
  SensorOps ops(*sim);
  sim->run_until(1.0);
  // armed and hovering-thrust level is not needed: a disarmed hexa dropped 5 mm onto the deck at
  // the deck's velocity, then armed-and-force-disarmed as the mission does at the switch
  const objects::TruckState s = truck.state(sim->time_s());
  physics::set_vehicle_state(
      sim->world(), 0, s.deck_centre_enu_m + Eigen::Vector3d(0, 0, kSkidDepth_m + 0.005),
      Eigen::Quaterniond(Eigen::AngleAxisd(s.yaw_rad, Eigen::Vector3d::UnitZ())),
      s.velocity_enu_m_s, Eigen::Vector3d::Zero());
  bool closed = false;
  while (!closed && sim->time_s() < 1.5) {
    sim->step();
    closed = call(ops, "sensor_read", {{"vehicle", 0}})["any"].get<bool>();
  }
  ASSERT_TRUE(closed);
  fc::CommandResult disarm = fc::CommandResult::kFailed;
  sim->post(0, [&](fc::FlightController& f) { disarm = f.disarm(true); });
  sim->run_until(sim->time_s() + 0.01);
  EXPECT_EQ(disarm, fc::CommandResult::kAccepted);
  ASSERT_EQ(sim->events().count(sim::EventType::kLandedOnTarget), 1u);

  // 10 s of riding (42 m of track): on the deck where it landed, switches closed, no crash
  const auto offset = [&] {
    const objects::TruckState t = truck.state(sim->time_s() - sim->physics_dt_s());
    return Eigen::Vector3d(Eigen::AngleAxisd(-t.yaw_rad, Eigen::Vector3d::UnitZ()) *
                           (sim->truth(0).position_enu_m - t.deck_centre_enu_m));
  };
  const Eigen::Vector3d start = offset();
  while (sim->time_s() < 11.5) {
    sim->step();
    ASSERT_LT((offset() - start).norm(), 0.01) << sim->time_s();
  }
  EXPECT_TRUE(call(ops, "sensor_read", {{"vehicle", 0}})["any"].get<bool>());
  EXPECT_EQ(sim->events().count(sim::EventType::kCrash), 0u);
  EXPECT_EQ(truck.state(sim->time_s()).carried_vehicles, std::vector<int>{0});
}

}  // namespace
}  // namespace uavsim::server::api
