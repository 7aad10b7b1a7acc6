// Whole flights flown only through the MAVLink endpoint: guided take-off, goto, land; an AUTO mission.
#include <cmath>

#include "test_gcs.hpp"

namespace uavsim::server::mavlink::testing {
namespace {

constexpr double kAltTolM = 0.5;
constexpr double kPosTolM = 1.0;
// the vehicle at a goal: the estimate's own offset from truth plus the hold error
constexpr double kArrivedPosTolM = 1.5;
constexpr double kSidewaysMaxM = 0.5;
// a mission item read back: lat/lon in 1e-7 deg, altitude through a float
constexpr double kItemLatLonTolE7 = 2;
constexpr double kItemAltTolM = 0.01;

class FlightTest : public EndpointTest {
 protected:
  static std::string texts(const TestGcs& g) {
    std::string out;
    for (const auto& t : g.all<msg::Statustext>()) out += std::string(get_string(t.text)) + "; ";
    return out;
  }
  // GUIDED, arm, take off to alt_m; returns when GLOBAL_POSITION_INT.relative_alt says it is there
  void take_off(TestGcs& g, double alt_m) {
    wait_gps_ready(g);
    ASSERT_EQ(command(g, MavCmd::DoSetMode, {1, 4}), 0);
    ASSERT_EQ(command(g, MavCmd::ComponentArmDisarm, {1}), 0);
    ASSERT_EQ(command(g, MavCmd::NavTakeoff, {0, 0, 0, 0, 0, 0, static_cast<float>(alt_m)}), 0);
    ASSERT_TRUE(step_until(g, [&] {
      const auto p = g.last<msg::GlobalPositionInt>();
      return p && std::abs(p->relative_alt / 1000.0 - alt_m) < kAltTolM;
    }, 30.0)) << "never reached take-off altitude in telemetry: relative_alt "
               << (g.last<msg::GlobalPositionInt>() ? g.last<msg::GlobalPositionInt>()->relative_alt : -1)
               << " mm, truth z " << sim_->truth(0).position_enu_m.z() << " m, home z "
               << sim_->fc(0).home_enu_m().z() << ", armed " << sim_->fc(0).armed() << ", texts: " << texts(g);
  }

  void land_and_wait_disarm(TestGcs& g) {
    ASSERT_EQ(command(g, MavCmd::NavLand), 0);
    ASSERT_TRUE(step_until(g, [&] {
      const auto hb = g.last<msg::Heartbeat>();
      return hb && hb->custom_mode == to_underlying(CopterMode::Land) &&
             !has_flag(hb->base_mode, MavModeFlag::SafetyArmed);
    }, 60.0)) << "never disarmed after LAND";
  }
};

TEST_F(FlightTest, GuidedTakeoffGotoLocalNedAndLand) {
  auto g = connect();
  take_off(*g, 10.0);
  ASSERT_TRUE(HasFatalFailure() == false);
  // go to local NED (10, 5, -10): 10 m north, 5 m east, 10 m up
  msg::SetPositionTargetLocalNed sp;
  sp.target_system = 1;
  sp.target_component = 1;
  sp.coordinate_frame = 1;
  sp.type_mask = 3576;  // position only
  sp.x = 10, sp.y = 5, sp.z = -10;
  g->send(sp);
  sync_client(*g);
  ASSERT_TRUE(step_until(*g, [&] {
    const auto p = g->last<msg::LocalPositionNed>();
    return p && std::hypot(p->x - 10.0, p->y - 5.0) < kPosTolM && std::abs(p->z + 10.0) < kAltTolM;
  }, 30.0));
  // telemetry is the estimate, and the estimate tracks the truth: the vehicle is really there (ENU x = east)
  EXPECT_NEAR(sim_->truth(0).position_enu_m.x(), 5.0, kArrivedPosTolM);
  EXPECT_NEAR(sim_->truth(0).position_enu_m.y(), 10.0, kArrivedPosTolM);
  // POSITION_TARGET_LOCAL_NED reports the goal in NED
  EXPECT_EQ(command(*g, MavCmd::RequestMessage, {85}), 0);
  ASSERT_TRUE(step_until(*g, [&] { return g->count<msg::PositionTargetLocalNed>() > 0; }, 1.0));
  const auto tgt = g->last<msg::PositionTargetLocalNed>();
  EXPECT_NEAR(tgt->x, 10.0, kPosTolM);  // the controller's current (shaped) target, near the goal
  EXPECT_NEAR(tgt->z, -10.0, kAltTolM);
  land_and_wait_disarm(*g);
}

TEST_F(FlightTest, BodyFrameVelocitySetpointMovesAlongTheHeading) {
  auto g = connect();
  take_off(*g, 5.0);
  const auto start = *g->last<msg::LocalPositionNed>();
  const double yaw = g->last<msg::Attitude>()->yaw;
  // 1 m/s forward in BODY_NED, re-sent every 0.5 s like a companion computer
  msg::SetPositionTargetLocalNed sp;
  sp.target_system = 1;
  sp.coordinate_frame = 8;
  sp.type_mask = 3527;  // velocity only
  sp.vx = 1.0f;
  for (int i = 0; i < 8; ++i) {
    g->send(sp);
    sync_client(*g);
    step_for(0.5);
  }
  ASSERT_TRUE(step_until(*g, [] { return true; }, 0.1));
  const auto end = *g->last<msg::LocalPositionNed>();
  const double dn = end.x - start.x, de = end.y - start.y;
  // 4 s at up to 1 m/s along the heading: moved forward 2..4.5 m, little sideways
  const double forward = dn * std::cos(yaw) + de * std::sin(yaw);
  const double side = -dn * std::sin(yaw) + de * std::cos(yaw);
  EXPECT_GT(forward, 2.0);
  EXPECT_LT(forward, 4.5);
  EXPECT_LT(std::abs(side), kSidewaysMaxM);
}

TEST_F(FlightTest, MissionItemWithCurrent2IsAGuidedGoto) {
  auto g = connect();
  take_off(*g, 8.0);
  // DroneKit simple_goto: MISSION_ITEM current=2, GLOBAL_RELATIVE_ALT, target (0, 0)
  const Geodetic dest = geodetic_from_ned(server_->config().origin, {-8.0, 6.0, 0.0});
  msg::MissionItem mi;
  mi.target_system = 0;
  mi.target_component = 0;
  mi.frame = 3;
  mi.command = cmd_id(MavCmd::NavWaypoint);
  mi.current = 2;
  mi.x = static_cast<float>(dest.lat_deg);
  mi.y = static_cast<float>(dest.lon_deg);
  mi.z = 12.0f;
  g->send(mi);
  sync_client(*g);
  ASSERT_TRUE(step_until(*g, [&] { return g->count<msg::MissionAck>() > 0; }, 1.0));
  EXPECT_EQ(g->last<msg::MissionAck>()->type, 0);
  ASSERT_TRUE(step_until(*g, [&] {
    const auto p = g->last<msg::LocalPositionNed>();
    // float degrees carry ~0.5 m of resolution at this latitude
    return p && std::hypot(p->x + 8.0, p->y - 6.0) < 1.5 && std::abs(p->z + 12.0) < kAltTolM;
  }, 30.0));
}

TEST_F(FlightTest, MissionUploadDownloadAndAutoFlight) {
  auto g = connect();
  const GeodeticOrigin& o = server_->config().origin;
  // home + three waypoints at 10 m relative: (10,0), (10,10), (0,10) NED metres
  const Eigen::Vector3d wps[3] = {{10, 0, 0}, {10, 10, 0}, {0, 10, 0}};
  auto item_for = [&](int seq) {
    msg::MissionItemInt it;
    it.target_system = 1;
    it.target_component = 1;
    it.seq = static_cast<std::uint16_t>(seq);
    it.frame = 6;
    it.autocontinue = 1;
    if (seq == 0) {
      it.command = cmd_id(MavCmd::NavWaypoint);
      it.frame = 0;
    } else if (seq == 1) {
      it.command = cmd_id(MavCmd::NavTakeoff);
      it.z = 10;
    } else {
      const Geodetic gd = geodetic_from_ned(o, wps[seq - 2]);
      it.command = cmd_id(MavCmd::NavWaypoint);
      it.x = static_cast<std::int32_t>(std::llround(gd.lat_deg * 1e7));
      it.y = static_cast<std::int32_t>(std::llround(gd.lon_deg * 1e7));
      it.z = 10;
    }
    return it;
  };
  ASSERT_EQ(upload_mission(*g, 5, item_for), 0);  // home, takeoff, 3 waypoints
  ASSERT_EQ(sim_->fc(0).mission().size(), 5u);

  // download it back with MISSION_REQUEST_LIST / MISSION_REQUEST_INT
  msg::MissionRequestList rl;
  rl.target_system = 1;
  g->send(rl);
  sync_client(*g);
  ASSERT_TRUE(step_until(*g, [&] { return g->count<msg::MissionCount>() > 0; }, 1.0));
  EXPECT_EQ(g->last<msg::MissionCount>()->count, 5);
  msg::MissionRequestInt ri;
  ri.target_system = 1;
  ri.seq = 3;
  g->send(ri);
  sync_client(*g);
  ASSERT_TRUE(step_until(*g, [&] { return g->count<msg::MissionItemInt>() > 0; }, 1.0));
  const auto back = *g->last<msg::MissionItemInt>();
  EXPECT_EQ(back.seq, 3);
  EXPECT_EQ(back.command, 16);
  EXPECT_NEAR(back.x, item_for(3).x, kItemLatLonTolE7);
  EXPECT_NEAR(back.y, item_for(3).y, kItemLatLonTolE7);
  EXPECT_NEAR(back.z, 10.0, kItemAltTolM);

  // fly it: GUIDED, arm, AUTO via MISSION_START
  wait_gps_ready(*g);
  ASSERT_EQ(command(*g, MavCmd::DoSetMode, {1, 4}), 0);
  ASSERT_EQ(command(*g, MavCmd::ComponentArmDisarm, {1}), 0);
  ASSERT_EQ(command(*g, MavCmd::MissionStart, {0, 0}), 0);
  ASSERT_TRUE(step_until(*g, [&] {
    for (const auto& r : g->all<msg::MissionItemReached>()) if (r.seq == 4) return true;
    return false;
  }, 90.0)) << "the last waypoint was never reported reached";
  std::vector<int> reached;
  for (const auto& r : g->all<msg::MissionItemReached>()) reached.push_back(r.seq);
  EXPECT_NE(std::find(reached.begin(), reached.end(), 2), reached.end());
  EXPECT_NE(std::find(reached.begin(), reached.end(), 3), reached.end());
  const auto p = g->last<msg::LocalPositionNed>();
  EXPECT_NEAR(p->x, 0.0, kArrivedPosTolM);
  EXPECT_NEAR(p->y, 10.0, kArrivedPosTolM);
  EXPECT_EQ(g->last<msg::Heartbeat>()->custom_mode, 3u);  // AUTO
}

TEST_F(FlightTest, MissionUploadTimesOutInSimTime) {
  auto g = connect();
  msg::MissionCount mc;
  mc.target_system = 1;
  mc.count = 3;
  g->send(mc);
  sync_client(*g);
  // nobody answers: the request is repeated about once a second, then the transfer is cancelled
  ASSERT_TRUE(step_until(*g, [&] { return g->count<msg::MissionAck>() > 0; }, 10.0));
  EXPECT_EQ(g->last<msg::MissionAck>()->type, 15);  // OPERATION_CANCELLED
  EXPECT_GE(g->count<msg::MissionRequest>(), 7u);
}

TEST_F(FlightTest, AnUploadInProgressIsNeitherClearedNorOverwrittenByAnother) {
  // a MISSION_CLEAR_ALL during an upload was ACCEPTED and then overwritten by the upload; a second
  // client's upload during the first was accepted and the last to finish won
  auto a = connect();
  auto b = connect();
  msg::MissionCount mc;
  mc.target_system = 1;
  mc.count = 3;
  a->send(mc);
  sync_client(*a);
  ASSERT_TRUE(step_until(*a, [&] { return a->count<msg::MissionRequest>() > 0; }, 1.0));
  // b's upload and b's clear are DENIED (14) while a's runs
  b->send(mc);
  sync_client(*b);
  ASSERT_TRUE(step_until(*b, [&] { return b->count<msg::MissionAck>() > 0; }, 1.0));
  EXPECT_EQ(b->last<msg::MissionAck>()->type, 14);
  EXPECT_EQ(b->count<msg::MissionRequest>() + b->count<msg::MissionRequestInt>(), 0u);
  msg::MissionClearAll ca;
  ca.target_system = 1;
  for (TestGcs* g : {b.get(), a.get()}) {
    const std::size_t acks = g->count<msg::MissionAck>();
    g->send(ca);
    sync_client(*g);
    ASSERT_TRUE(step_until(*g, [&] { return g->count<msg::MissionAck>() > acks; }, 1.0));
    EXPECT_EQ(g->last<msg::MissionAck>()->type, 14);
  }
  // a's upload was not disturbed: it completes (restarted by a new count from a, which is allowed)
  const GeodeticOrigin& o = server_->config().origin;
  auto item_for = [&](int seq) {
    msg::MissionItemInt it;
    it.frame = seq == 0 ? 0 : 6;
    it.command = seq == 1 ? 22 : 16;
    it.z = 10;
    if (seq == 2) {
      const Geodetic gd = geodetic_from_ned(o, {5, 0, 0});
      it.x = static_cast<std::int32_t>(std::llround(gd.lat_deg * 1e7));
      it.y = static_cast<std::int32_t>(std::llround(gd.lon_deg * 1e7));
    }
    return it;
  };
  ASSERT_EQ(upload_mission(*a, 3, item_for), 0);
  EXPECT_EQ(sim_->fc(0).mission().size(), 3u);
  // with no upload running, b may clear it
  const std::size_t acks = b->count<msg::MissionAck>();
  b->send(ca);
  sync_client(*b);
  ASSERT_TRUE(step_until(*b, [&] { return b->count<msg::MissionAck>() > acks; }, 1.0));
  EXPECT_EQ(b->last<msg::MissionAck>()->type, 0);
  EXPECT_EQ(sim_->fc(0).mission().size(), 1u);  // home alone, as after any clear
}

TEST_F(FlightTest, MissionClearAllAndSetCurrent) {
  auto g = connect();
  msg::MissionClearAll ca;
  ca.target_system = 1;
  g->send(ca);
  sync_client(*g);
  ASSERT_TRUE(step_until(*g, [&] { return g->count<msg::MissionAck>() > 0; }, 1.0));
  EXPECT_EQ(g->last<msg::MissionAck>()->type, 0);
  msg::MissionSetCurrent sc;
  sc.target_system = 1;
  sc.seq = 0;
  const std::size_t before = g->count<msg::MissionCurrent>();
  g->send(sc);
  sync_client(*g);
  ASSERT_TRUE(step_until(*g, [&] { return g->count<msg::MissionCurrent>() > before; }, 0.1));
}

}  // namespace
}  // namespace uavsim::server::mavlink::testing
