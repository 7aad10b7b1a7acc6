// The mode objects alone, over a mode context the test builds from its own state (no
// FlightController, no sensors, no cascade): what each mode needs and allows, the state a mode
// keeps (BRAKE's latch, RTL's stage, AUTO's phase, STABILIZE's held collective), and whole RTL
// returns and AUTO missions flown by a vehicle that follows the position setpoint exactly.
#include "fc/flight_modes.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "fc/mode_context.hpp"
#include "uavsim/common/angles.hpp"

namespace uavsim::server::fc {
namespace {

constexpr double kTol = 1e-12;
// the flight controller's control step (400 Hz)
constexpr double kDtS = 0.0025;
// speeds compared with a limit: the carrot's last step may round above it
constexpr double kSpeedTolM_S = 1e-6;
// positions the modes hold exactly, up to round-off
constexpr double kPosTolM = 1e-9;
// the take-off's end height over home
constexpr double kTakeoffAltTolM = 0.5;

TEST(FlightModes, NeedsAndAllowsAsArduCopter) {
  FlightModes modes;
  // ArduCopter's requires_GPS and allows_arming, and the modes that read the pilot's sticks
  struct Row {
    Mode mode;
    bool position, arming, pilot;
  };
  const Row rows[] = {
      {Mode::kStabilize, false, true, true}, {Mode::kAltHold, false, true, true},
      {Mode::kGuided, true, true, false},    {Mode::kLoiter, true, true, true},
      {Mode::kBrake, true, false, false},    {Mode::kLand, false, false, false},
      {Mode::kRtl, true, false, false},      {Mode::kAuto, true, false, false},
  };
  for (const Row& r : rows) {
    const FlightMode& m = modes.of(r.mode);
    EXPECT_EQ(m.id(), r.mode);
    EXPECT_EQ(m.needs_position(), r.position) << mode_name(r.mode);
    EXPECT_EQ(m.allows_arming(), r.arming) << mode_name(r.mode);
    EXPECT_EQ(m.reads_pilot(), r.pilot) << mode_name(r.mode);
  }
  // LAND and RTL disarm on the ground at once and end the flight at touchdown; LAND is always
  // landing
  EXPECT_TRUE(modes.land.disarms_when_landed() && modes.land.landing() &&
              modes.land.ends_flight_at_touchdown());
  EXPECT_TRUE(modes.rtl.disarms_when_landed() && modes.rtl.ends_flight_at_touchdown());
  EXPECT_FALSE(modes.automatic.disarms_when_landed());
}

// What a mode needs from the cascade, faked: counts the take-off restarts.
class FakeCascade final : public CascadePort {
 public:
  void restart_for_takeoff() override { ++restarts; }
  double collective_n() const override { return collective; }
  double hover_thrust_n() const override { return hover; }
  double max_thrust_n() const override { return max; }

  int restarts = 0;
  double collective = 0.0;
  double hover = 14.715;  // 1.5 kg * 9.81
  double max = 30.0;
};

// The state a flight controller owns for its modes, owned here instead, armed and hovering at the
// origin with home on the ground below. step() runs one control step of a mode, then moves the
// estimate as a vehicle that tracks the position setpoint exactly would: to the setpoint's position
// on the axes it holds, along its velocity on the others.
struct ModeBench {
  ModeBench() {
    flight.armed = true;
    flight.landed = false;
    est.gps_ok = true;
    home.set = true;
    mission.items.push_back(MissionItem{});  // item 0: home
  }

  ModeContext context() {
    return ModeContext({est, now_s, params, home},
                       {flight, command, yaw, nav, pilot, guided, mission, texts}, cascade);
  }
  // the shared rules' part of entering a mode (modes.cpp: init_mode_state), then the mode's enter()
  void enter(FlightMode& mode) {
    ModeContext c = context();
    nav.active = false;
    nav.hold_position_enu_m = c.stopping_point();
    mode.enter(c, !flight.landed);
  }
  void step(FlightMode& mode) {
    now_s += kDtS;
    ModeContext c = context();
    mode.update(c, kDtS);
    const PositionSetpoint& sp = command.setpoint;
    ASSERT_EQ(command.kind, ControlKind::kPosition);
    Eigen::Vector3d& p = est.position_enu_m;
    const Eigen::Vector3d moved = p + sp.velocity_enu_m_s * kDtS;
    p.head<2>() = sp.use_pos_xy ? sp.position_enu_m.head<2>() : moved.head<2>();
    p.z() = sp.use_pos_z ? sp.position_enu_m.z() : moved.z();
    est.velocity_enu_m_s = sp.velocity_enu_m_s;
  }
  std::vector<int> drain_reached() {
    std::vector<int> out;
    mission.reached.drain([&out](int seq) { out.push_back(seq); });
    return out;
  }
  std::vector<std::string> drain_texts() {
    std::vector<std::string> out;
    texts.drain([&out](const FixedText& t) { out.emplace_back(t.text.data()); });
    return out;
  }
  double height_m() const { return est.position_enu_m.z() - home.position_enu_m.z(); }

  EstimatedState est;
  double now_s = 100.0;
  ParamTable params{5000.0};
  Home home;
  FlightState flight;
  CascadeCommand command;
  YawState yaw;
  NavState nav;
  PilotState pilot;
  GuidedState guided;
  MissionState mission;
  StatusTexts texts;
  FakeCascade cascade;
  FlightModes modes;
};

TEST(FlightModes, StabilizeHoldsTheCollectiveItWasEnteredWith) {
  ModeBench b;
  b.cascade.collective = 14.7;  // what the mixer gave last step
  ModeContext c = b.context();
  b.modes.stabilize.enter(c, true);
  EXPECT_EQ(b.command.fixed_thrust_n, 14.7);
  b.modes.stabilize.enter(c, false);  // on the ground: idle
  EXPECT_EQ(b.command.fixed_thrust_n, 0.0);
}

TEST(FlightModes, AutoPhasesFollowTheItems) {
  ModeBench b;
  MissionItem land_here;  // LAND without a position: descend where it is
  land_here.kind = MissionItem::Kind::kLand;
  land_here.position_valid = false;
  MissionItem rtl;
  rtl.kind = MissionItem::Kind::kRtl;
  MissionItem yaw;
  yaw.kind = MissionItem::Kind::kConditionYaw;
  yaw.yaw_enu_rad = 3.0 * common::kPi / 2.0;  // 270 deg ENU = -90 deg once wrapped
  b.mission.items = {MissionItem{}, land_here, rtl, yaw};
  AutoMode& a = b.modes.automatic;
  ModeContext c = b.context();

  a.start_item(c, 1);
  EXPECT_TRUE(a.landing());
  EXPECT_TRUE(a.ends_flight_at_touchdown());
  // RTL item: the RTL object climbs first (not landing yet), but a touchdown would end the flight
  a.start_item(c, 2);
  EXPECT_FALSE(a.landing());
  EXPECT_TRUE(a.ends_flight_at_touchdown());
  EXPECT_FALSE(b.modes.rtl.landing());
  // CONDITION_YAW: the heading target, wrapped to (-pi, pi]
  a.start_item(c, 3);
  EXPECT_NEAR(b.yaw.target_rad, -common::kPi / 2.0, kTol);
  EXPECT_TRUE(b.yaw.fixed);
  EXPECT_FALSE(a.ends_flight_at_touchdown());
  // past the end: mission complete, holding at the last item
  a.complete_item(c);
  EXPECT_EQ(b.mission.current, 3);
  EXPECT_FALSE(a.landing());
  EXPECT_EQ(b.drain_reached(), std::vector<int>{3});
  EXPECT_EQ(b.drain_texts(), std::vector<std::string>{"Mission complete"});
}

TEST(FlightModes, LandDescendsWhereTheHoldWas) {
  ModeBench b;
  b.nav.hold_position_enu_m = Eigen::Vector3d(3.0, -4.0, 10.0);
  ModeContext c = b.context();
  b.modes.land.enter(c, true);
  EXPECT_EQ(b.nav.land_xy_enu_m, Eigen::Vector3d(3.0, -4.0, 10.0));
}

TEST(FlightModes, BrakeStopsThenLatchesAHoldWhereItStopped) {
  ModeBench b;
  b.est.position_enu_m = Eigen::Vector3d(10.0, 5.0, 20.0);
  b.est.velocity_enu_m_s = Eigen::Vector3d(6.0, 0.0, 0.0);
  BrakeMode& brake = b.modes.brake;
  b.enter(brake);
  const double hold_z = b.nav.hold_position_enu_m.z();  // the stopping point's height
  ModeContext c = b.context();
  // moving: a velocity target of zero horizontally, the height held; no position hold yet
  brake.update(c, kDtS);
  EXPECT_EQ(b.command.kind, ControlKind::kPosition);
  EXPECT_FALSE(b.command.setpoint.use_pos_xy);
  EXPECT_TRUE(b.command.setpoint.use_vel_xy && b.command.setpoint.use_pos_z);
  EXPECT_EQ(b.command.setpoint.velocity_enu_m_s, Eigen::Vector3d::Zero());
  EXPECT_EQ(b.command.setpoint.position_enu_m.z(), hold_z);
  // still faster than the latch speed (0.2 m/s): no hold
  b.est.position_enu_m.x() = 14.0;
  b.est.velocity_enu_m_s.x() = 0.5;
  brake.update(c, kDtS);
  EXPECT_FALSE(b.command.setpoint.use_pos_xy);
  // slow enough: it holds where it is now ...
  b.est.position_enu_m.x() = 14.5;
  b.est.velocity_enu_m_s.x() = 0.1;
  brake.update(c, kDtS);
  EXPECT_TRUE(b.command.setpoint.use_pos_xy);
  const Eigen::Vector3d latched(14.5, 5.0, hold_z);
  EXPECT_EQ(b.command.setpoint.position_enu_m, latched);
  // ... and keeps that point when the vehicle drifts on and speeds up again
  b.est.position_enu_m.x() = 16.0;
  b.est.velocity_enu_m_s.x() = 1.0;
  brake.update(c, kDtS);
  EXPECT_TRUE(b.command.setpoint.use_pos_xy);
  EXPECT_EQ(b.command.setpoint.position_enu_m, latched);
  // entering BRAKE again forgets the latch
  b.enter(brake);
  brake.update(c, kDtS);
  EXPECT_FALSE(b.command.setpoint.use_pos_xy);
}

TEST(FlightModes, RtlClimbsReturnsLoitersThenLands) {
  ModeBench b;
  ASSERT_TRUE(b.params.set("RTL_ALT", 2500.0));        // 25 m
  ASSERT_TRUE(b.params.set("RTL_SPEED", 300.0));       // 3 m/s home, not WPNAV_SPEED
  ASSERT_TRUE(b.params.set("RTL_LOIT_TIME", 4000.0));  // 4 s over home
  const DerivedParams& d = b.params.derived();
  ASSERT_LT(d.rtl_speed_m_s, d.wp_speed_m_s);
  b.home.position_enu_m = Eigen::Vector3d(2.0, 1.0, 0.0);
  const Eigen::Vector3d start(32.0, 41.0, 6.0);  // 50 m from home, 6 m up
  b.est.position_enu_m = start;
  RtlMode& rtl = b.modes.rtl;
  b.enter(rtl);
  // climb: straight up to RTL_ALT above home (higher than where it is)
  const double alt = b.home.position_enu_m.z() + d.rtl_alt_m;
  EXPECT_EQ(b.nav.carrot.destination(), Eigen::Vector3d(start.x(), start.y(), alt));

  const Eigen::Vector3d home_at_alt(b.home.position_enu_m.x(), b.home.position_enu_m.y(), alt);
  double climb_end_s = -1.0, near_home_s = -1.0, land_s = -1.0;
  double max_climb_m_s = 0.0, max_return_xy_m_s = 0.0;
  const double t0 = b.now_s;
  while (land_s < 0.0 && b.now_s - t0 < 120.0) {
    b.step(rtl);
    const double speed_xy = b.est.velocity_enu_m_s.head<2>().norm();
    if (climb_end_s < 0.0) {
      max_climb_m_s = std::max(max_climb_m_s, b.est.velocity_enu_m_s.z());
      EXPECT_NEAR((b.est.position_enu_m - start).head<2>().norm(), 0.0, kTol);
      if (b.nav.carrot.destination() == home_at_alt) {
        // the return starts once the carrot is at RTL_ALT, the vehicle with it
        climb_end_s = b.now_s;
        EXPECT_NEAR(b.est.position_enu_m.z(), alt, kPosTolM);
      }
    } else if (near_home_s < 0.0) {
      max_return_xy_m_s = std::max(max_return_xy_m_s, speed_xy);
      EXPECT_NEAR(b.est.position_enu_m.z(), alt, kPosTolM);
      if (b.nav.carrot.arrived() &&
          (b.est.position_enu_m - home_at_alt).head<2>().norm() < d.wp_radius_m) {
        near_home_s = b.now_s;
      }
    } else {
      EXPECT_NEAR((b.est.position_enu_m - home_at_alt).norm(), 0.0, kPosTolM);  // loitering
    }
    EXPECT_FALSE(rtl.landing() && near_home_s < 0.0);
    if (rtl.landing()) land_s = b.now_s;
  }
  ASSERT_GT(climb_end_s, 0.0);
  ASSERT_GT(near_home_s, 0.0);
  ASSERT_GT(land_s, 0.0);
  // the climb at WPNAV_SPEED_UP at most, the return at RTL_SPEED (reached: 50 m is long enough)
  EXPECT_LE(max_climb_m_s, d.wp_speed_up_m_s + kSpeedTolM_S);
  EXPECT_NEAR(max_return_xy_m_s, d.rtl_speed_m_s, kSpeedTolM_S);
  // RTL_LOIT_TIME over home: the mode sees the vehicle there in the step it gets there or the next
  EXPECT_GE(land_s - near_home_s, d.rtl_loit_time_s - 1e-9);
  EXPECT_LT(land_s - near_home_s, d.rtl_loit_time_s + 2.0 * kDtS + 1e-9);

  // land (from the next step): over home, at LAND_SPEED_HIGH while higher than 10 m above home,
  // then LAND_SPEED
  b.step(rtl);
  const PositionSetpoint& sp = b.command.setpoint;
  EXPECT_EQ(b.nav.land_xy_enu_m.head<2>(), b.home.position_enu_m.head<2>());
  EXPECT_TRUE(sp.use_pos_xy && !sp.use_pos_z);
  EXPECT_EQ(sp.velocity_enu_m_s.z(), -d.land_speed_high_m_s);
  EXPECT_FALSE(b.nav.active);
  while (b.height_m() > 10.0) b.step(rtl);
  b.step(rtl);
  EXPECT_EQ(sp.velocity_enu_m_s.z(), -d.land_speed_m_s);
  EXPECT_EQ(sp.position_enu_m.head<2>(), b.home.position_enu_m.head<2>());
  EXPECT_TRUE(rtl.landing());
}

TEST(FlightModes, AutoFliesTheItemsInTurnAndReportsEachReached) {
  ModeBench b;
  const DerivedParams& d = b.params.derived();
  b.flight.landed = true;  // armed on the ground at home
  // a leg reaches WPNAV_SPEED v when it is longer than the v^2 / (2 a) to speed up plus as much to
  // stop: 10^2 / 2.5 = 40 m with the defaults
  constexpr double kLegM = 60.0;
  ASSERT_GT(kLegM, d.wp_speed_m_s * d.wp_speed_m_s / d.wp_accel_m_s2);
  MissionItem takeoff;
  takeoff.kind = MissionItem::Kind::kTakeoff;
  takeoff.position_enu_m = Eigen::Vector3d(0.0, 0.0, 10.0);  // 10 m above home
  MissionItem wp_a;
  wp_a.position_enu_m = Eigen::Vector3d(kLegM, 0.0, 10.0);
  MissionItem wp_b = wp_a;  // hold 3 s there
  wp_b.position_enu_m = Eigen::Vector3d(kLegM, kLegM, 10.0);
  wp_b.param_s_or_m_s = 3.0;
  MissionItem slower;  // DO_CHANGE_SPEED to half WPNAV_SPEED
  slower.kind = MissionItem::Kind::kChangeSpeed;
  slower.param_s_or_m_s = d.wp_speed_m_s / 2.0;
  MissionItem wp_c;
  wp_c.position_enu_m = Eigen::Vector3d(0.0, kLegM, 10.0);
  MissionItem land;
  land.kind = MissionItem::Kind::kLand;
  land.position_enu_m = Eigen::Vector3d(0.0, 0.0, 0.0);
  b.mission.items = {MissionItem{}, takeoff, wp_a, wp_b, slower, wp_c, land};
  AutoMode& a = b.modes.automatic;

  // entering AUTO on the ground starts the take-off: the vehicle leaves the ground, the cascade
  // starts fresh
  b.enter(a);
  EXPECT_EQ(b.mission.current, 1);
  EXPECT_FALSE(b.flight.landed);
  EXPECT_TRUE(b.flight.takeoff_active);
  EXPECT_EQ(b.cascade.restarts, 1);
  EXPECT_EQ(b.drain_texts(), std::vector<std::string>{"Takeoff"});
  EXPECT_EQ(b.nav.carrot.destination(), Eigen::Vector3d(0.0, 0.0, 10.0));

  struct Reached {
    int seq;
    double t_s;
    Eigen::Vector3d position_enu_m;
  };
  std::vector<Reached> reached;
  double max_xy_m_s[7] = {};  // per current item
  double at_wp_b_s = -1.0;
  const double t0 = b.now_s;
  bool airborne = false;
  while (!(airborne && b.height_m() <= 0.0) && b.now_s - t0 < 300.0) {
    b.step(a);
    airborne = airborne || b.height_m() > 1.0;
    const int current = b.mission.current;
    max_xy_m_s[current] = std::max(max_xy_m_s[current], b.est.velocity_enu_m_s.head<2>().norm());
    if (current == 3 && at_wp_b_s < 0.0 && b.nav.carrot.arrived() &&
        (b.est.position_enu_m - wp_b.position_enu_m).norm() < d.wp_radius_m) {
      at_wp_b_s = b.now_s;
    }
    for (int seq : b.drain_reached()) reached.push_back({seq, b.now_s, b.est.position_enu_m});
  }
  // every item up to the land reached in turn; the land's own MISSION_ITEM_REACHED comes at
  // touchdown (the land detector's, not the mode's)
  ASSERT_EQ(reached.size(), 5u);
  for (int k = 0; k < 5; ++k) EXPECT_EQ(reached[k].seq, k + 1);
  EXPECT_EQ(b.mission.current, 6);
  EXPECT_TRUE(a.landing());
  // the take-off ends at 10 m over home, a waypoint within WPNAV_RADIUS of it
  EXPECT_NEAR(reached[0].position_enu_m.z(), 10.0, kTakeoffAltTolM);
  EXPECT_LT((reached[1].position_enu_m - wp_a.position_enu_m).norm(), d.wp_radius_m);
  EXPECT_LT((reached[2].position_enu_m - wp_b.position_enu_m).norm(), d.wp_radius_m);
  // wp_b holds its 3 s (the mode sees the vehicle there this step or the next)
  ASSERT_GT(at_wp_b_s, 0.0);
  EXPECT_GE(reached[2].t_s - at_wp_b_s, 3.0 - 1e-9);
  EXPECT_LT(reached[2].t_s - at_wp_b_s, 3.0 + 2.0 * kDtS + 1e-9);
  // DO_CHANGE_SPEED is done at once and slows the next leg to its speed; the legs before it fly at
  // WPNAV_SPEED
  EXPECT_EQ(reached[3].t_s, reached[2].t_s);
  EXPECT_NEAR(max_xy_m_s[2], d.wp_speed_m_s, kSpeedTolM_S);
  EXPECT_NEAR(max_xy_m_s[5], d.wp_speed_m_s / 2.0, kSpeedTolM_S);
  // the land item flies to its point at the current height, then descends there
  EXPECT_EQ(b.nav.land_xy_enu_m.head<2>(), land.position_enu_m.head<2>());
  EXPECT_NEAR((b.est.position_enu_m - land.position_enu_m).head<2>().norm(), 0.0, kPosTolM);
}

}  // namespace
}  // namespace uavsim::server::fc
