// What the gimbal reports over MAVLink while it slews: the camera's actual attitude, its
// stabilisation loop's lag included (a mission places what its camera sees with it), wired as
// server_app.cpp wires it.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <map>
#include <memory>
#include <optional>

#include "app/gimbal_bridge.hpp"
#include "mavlink_endpoint/test_gcs.hpp"
#include "objects/world_objects.hpp"
#include "physics/object_bodies.hpp"
#include "uavsim/common/angles.hpp"
#include "uavsim/common/frames.hpp"

namespace uavsim::server::mavlink::testing {
namespace {

namespace frames = ::uavsim::common::frames;
using common::kDegToRad;
// The report against the camera body as placed for the same step: float quaternion, and the body
// turned by the vehicle's rotation within one physics step (it stands on the ground)
constexpr double kMatch_deg = 0.1;
constexpr double kSettled_deg = 0.5;  // the gimbal's hold error after a second

// mbzirc2020.xml (two quads, forward cameras on gimbals) with the field's gimbal: 50 ms loop, 180
// deg/s, 1000 deg/s^2; the endpoint, the objects and the gimbal bridge as uavsim-server has them
class GimbalReportTest : public EndpointTest {
 protected:
  void SetUp() override {
    physics::ComposeOptions o;
    o.models_dir = UAVSIM_MODELS_DIR;
    sim::SimConfig c;
    c.field.gimbal = {0.05, 180.0 * kDegToRad, 1000.0 * kDegToRad};
    sim_ = std::make_unique<sim::Simulation>(
        physics::World::load(std::string(UAVSIM_MODELS_DIR) + "/worlds/mbzirc2020.xml", o), c);
    objects_ = objects::add_world_objects(*sim_);
    ASSERT_NE(objects_.gimbals, nullptr);
    EndpointConfig ec;
    ec.base_port = 0;
    objects::GimbalSet* gimbals = objects_.gimbals;
    ec.gimbal_attitude = [this, gimbals](std::size_t v) {
      return app::gimbal_device_attitude(*gimbals, *sim_, v);
    };
    server_ = std::make_unique<MavlinkServer>(*sim_, ec);
    server_->schedule(sim_->schedule());
    MavlinkServer* ms = server_.get();
    bridge_ = std::make_unique<app::MavlinkGimbalBridge>(
        *gimbals, [ms](size_t v) -> const GimbalState& { return ms->gimbal(v); });
    sim_->schedule().add(sim::Phase::kPostControl, "gimbal_bridge",
                         [this] { bridge_->update(*sim_); });
  }
  void TearDown() override {
    EndpointTest::TearDown();
    bridge_.reset();
  }

  // the reported attitude turned into the world (ENU, the camera body's axes: x along the optical
  // axis, z up when level) with the vehicle's true heading then (the report's yaw is relative to
  // it)
  static Eigen::Quaterniond reported_enu(const msg::GimbalDeviceAttitudeStatus& m,
                                         double heading_ned_rad) {
    const Eigen::Quaterniond q_vehicle(m.q[0], m.q[1], m.q[2], m.q[3]);
    return frames::q_enu_flu_from_q_ned_frd(
        Eigen::AngleAxisd(heading_ned_rad, Eigen::Vector3d::UnitZ()) * q_vehicle.normalized());
  }

  objects::ObjectSet objects_;
  std::unique_ptr<app::MavlinkGimbalBridge> bridge_;
};

TEST_F(GimbalReportTest, DuringASlewTheReportedAttitudeLagsTheCommandAndIsTheCamerasOwn) {
  auto g = connect();
  // GIMBAL_DEVICE_ATTITUDE_STATUS every 10 ms; level first (the world's forward gimbal)
  EXPECT_EQ(command(*g, MavCmd::SetMessageInterval, {285, 10000}), 0);
  ASSERT_TRUE(step_until(
      *g, [&] { return g->count<msg::GimbalDeviceAttitudeStatus>() > 0; }, 1.0));
  // DO_MOUNT_CONTROL, 60 deg down: handled in the next control step, stepped from here on
  msg::CommandLong c;
  c.command = cmd_id(MavCmd::DoMountControl);
  c.target_system = 1;
  c.target_component = 1;
  c.param1 = -60.0f;
  c.param7 = 2.0f;  // MAV_MOUNT_MODE_MAVLINK_TARGETING
  g->send(c);
  sync_client(*g);
  const double commanded_s = sim_->time_s();
  const int body = objects_.gimbals->gimbals()[0].body_id;
  // per control step (by its time_boot_ms): the camera body's orientation and the vehicle's heading
  // as the step's telemetry sees them (it is sent before the step's physics)
  struct Seen {
    Eigen::Quaterniond camera_enu;
    double heading_ned_rad;
  };
  std::map<std::uint32_t, Seen> seen;
  while (sim_->time_s() < commanded_s + 1.0) {
    seen[static_cast<std::uint32_t>(std::llround(sim_->time_s() * 1e3))] = {
        physics::body_orientation_enu(sim_->world(), body),
        frames::euler_from_q_ned_frd(frames::q_ned_frd_from_q_enu_flu(sim_->truth(0).q_enu_body))
            .yaw_rad};
    for (int k = 0; k < sim_->control_decimation(); ++k) sim_->step();
  }
  ASSERT_TRUE(server_->flush_queued());
  ASSERT_TRUE(wait_for([&] {
    g->poll_once(5);
    const auto m = g->last<msg::GimbalDeviceAttitudeStatus>();
    return m && m->time_boot_ms + 20 >= sim_->time_s() * 1e3;
  }));
  ASSERT_TRUE(g->last<msg::CommandAck>());
  EXPECT_EQ(g->last<msg::CommandAck>()->result, 0);
  int checks = 0;
  double worst_deg = 0.0, most_lag_deg = 0.0, last_pitch_deg = 0.0;
  for (const msg::GimbalDeviceAttitudeStatus& m : g->all<msg::GimbalDeviceAttitudeStatus>()) {
    const auto it = seen.find(m.time_boot_ms);
    if (it == seen.end()) continue;  // before the command
    ++checks;
    EXPECT_TRUE(has_flag(m.flags, GimbalDeviceFlags::YawInVehicleFrame));
    worst_deg = std::max(
        worst_deg,
        reported_enu(m, it->second.heading_ned_rad).angularDistance(it->second.camera_enu) /
            kDegToRad);
    const Eigen::Quaterniond q(m.q[0], m.q[1], m.q[2], m.q[3]);
    last_pitch_deg = frames::euler_from_q_ned_frd(q).pitch_rad / kDegToRad;
    most_lag_deg = std::max(most_lag_deg, std::abs(last_pitch_deg - -60.0));
  }
  EXPECT_GT(checks, 50);
  EXPECT_LT(worst_deg, kMatch_deg) << "the report is not the camera's attitude";
  // 60 deg at no more than 180 deg/s: a third of a second behind the command at least
  EXPECT_GT(most_lag_deg, 45.0) << "the report does not lag the command";
  EXPECT_NEAR(last_pitch_deg, -60.0, kSettled_deg);  // settled after a second
}

}  // namespace
}  // namespace uavsim::server::mavlink::testing
