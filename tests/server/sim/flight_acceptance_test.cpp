// Issue 2's acceptance flights, in the full MuJoCo simulation with the flight-controller emulation,
// driven through Simulation::post (the path the MAVLink endpoint uses). Tolerances are the issue's.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include "sim_fixture.hpp"
#include "uavsim/common/angles.hpp"

namespace uavsim::server::sim {
namespace {

using testing::goto_enu;
using testing::make_sim;
using testing::take_off;
using testing::wrap_pi;
using testing::yaw_of;

constexpr double kHoldTolM = 0.2;
constexpr double kSettleTolM = 1.0;
constexpr double kMaxOvershootM = 1.5;
constexpr double kPassTolM = 1.0;
// altitude held through a level 20 m move (the brief's figure)
constexpr double kMoveAltTolM = 0.15;
// altitude overshoot after a goto at the end of a take-off: the estimate's own offset from truth (baro
// noise 0.05 m, a few cm) plus the vertical position loop's settling (before the fix: 0.45-0.95 m)
constexpr double kTakeoffOvershootM = 0.2;
// hover body-rate RMS bound, between the measured ~0.035-0.04 rad/s and the old 0.055-0.065 rad/s
constexpr double kHoverRateJitterRad_S = 0.047;
// a lost rotor: LAND descends at LAND_SPEED_HIGH 1.5 m/s, the loss transient may add a little; the
// crash detector's hard-landing speed is 3 m/s. Tilt: ANGLE_MAX 30 deg plus the loss transient.
constexpr double kDeadRotorMaxSinkM_S = 2.5;
constexpr double kDeadRotorMaxTiltRad = 40.0 * common::kPi / 180.0;
constexpr double kYawSettleTolRad = 3.0 * common::kPi / 180.0;
constexpr double kYawStoppedRateRad_S = 0.02;

class EveryFrame : public ::testing::TestWithParam<const char*> {};

// take off to 10 m and hold within +-0.2 m (truth) for 60 s of sim time
TEST_P(EveryFrame, TakesOffAndHoldsAltitudeFor60s) {
  auto sim = make_sim(GetParam());
  const double target_z = sim->truth(0).position_enu_m.z() + 10.0;  // 10 m above where it stands
  take_off(*sim, 10.0);
  sim->run_until(sim->time_s() + 5.0);  // settle
  double worst = 0.0;
  const double end = sim->time_s() + 60.0;
  while (sim->time_s() < end) {
    sim->step();
    worst = std::max(worst, std::abs(sim->truth(0).position_enu_m.z() - target_z));
  }
  EXPECT_LT(worst, kHoldTolM) << GetParam();
  EXPECT_EQ(sim->events().count(EventType::kCrash), 0u);
}

// a 20 m step in x settles within 1 m with at most 1.5 m overshoot
TEST_P(EveryFrame, StepOf20mSettlesWithLimitedOvershoot) {
  auto sim = make_sim(GetParam());
  take_off(*sim, 10.0);
  sim->run_until(sim->time_s() + 3.0);
  const Eigen::Vector3d start = sim->truth(0).position_enu_m;
  const Eigen::Vector3d goal = start + Eigen::Vector3d(20.0, 0.0, 0.0);
  goto_enu(*sim, Eigen::Vector3d(goal.x(), goal.y(), 10.0));
  double max_x = -1e9;
  const double end = sim->time_s() + 30.0;
  while (sim->time_s() < end) {
    sim->step();
    max_x = std::max(max_x, sim->truth(0).position_enu_m.x());
  }
  EXPECT_LT((sim->truth(0).position_enu_m - Eigen::Vector3d(goal.x(), goal.y(), 10.0)).norm(), kSettleTolM);
  EXPECT_LE(max_x - goal.x(), kMaxOvershootM);
}

// a relative 90 deg yaw clockwise (as CONDITION_YAW asks it, in ENU: -90 deg) settles
TEST_P(EveryFrame, YawOf90DegSettles) {
  auto sim = make_sim(GetParam());
  take_off(*sim, 10.0);
  const double yaw0 = yaw_of(sim->truth(0).q_enu_body);
  sim->post(0, [](fc::FlightController& f) {
    EXPECT_EQ(f.set_yaw({-90.0 * common::kPi / 180.0, true, 0.0}), fc::CommandResult::kAccepted);
  });
  sim->run_until(sim->time_s() + 15.0);
  // clockwise seen from above is negative ENU yaw
  const double turned = wrap_pi(yaw_of(sim->truth(0).q_enu_body) - yaw0);
  EXPECT_NEAR(turned, -common::kPi / 2, kYawSettleTolRad);
  EXPECT_LT(std::abs(sim->truth(0).rate_body_rad_s.z()), kYawStoppedRateRad_S);  // stopped turning
}

// steady hover: truth roll/pitch body-rate jitter stays small (RMS over 10 s). GPS position noise
// reaches the attitude through the estimator and the velocity loop; with PSC_VELXY_D 0.5 this was
// 0.055 (quad) / 0.065 (hexa) rad/s, with 0.25 it is ~0.035 / 0.04 rad/s
TEST_P(EveryFrame, HoverBodyRateJitterIsSmall) {
  auto sim = make_sim(GetParam());
  take_off(*sim, 5.0);
  sim->run_until(sim->time_s() + 5.0);
  double sum_sq = 0.0;
  int n = 0;
  const double end = sim->time_s() + 10.0;
  while (sim->time_s() < end) {
    sim->step();
    sum_sq += sim->truth(0).rate_body_rad_s.head<2>().squaredNorm() / 2.0;
    ++n;
  }
  const double rms = std::sqrt(sum_sq / n);
  std::printf("[%s] hover roll/pitch rate RMS %.4f rad/s\n", GetParam(), rms);
  EXPECT_LT(rms, kHoverRateJitterRad_S);
}

// a goto sent the moment take-off gets near its altitude (still climbing at ~0.5 m/s) levels off
// without overshooting: the carrot's vertical velocity must not be carried into the level leg
TEST_P(EveryFrame, GotoAtTheEndOfTakeoffDoesNotOvershootAltitude) {
  auto sim = make_sim(GetParam());
  const double ground_z = sim->truth(0).position_enu_m.z();
  take_off(*sim, 5.0);
  const Eigen::Vector3d est = sim->fc(0).estimate().position_enu_m;
  goto_enu(*sim, Eigen::Vector3d(est.x() + 20.0, est.y(), sim->fc(0).home_enu_m().z() + 5.0));
  double max_z = -1e9;
  const double end = sim->time_s() + 20.0;
  while (sim->time_s() < end) {
    sim->step();
    max_z = std::max(max_z, sim->truth(0).position_enu_m.z());
  }
  EXPECT_LT(max_z - (ground_z + 5.0), kTakeoffOvershootM) << GetParam();
}

INSTANTIATE_TEST_SUITE_P(QuadAndHexa, EveryFrame, ::testing::Values("empty.xml", "hexa.xml"));

// hover at 5 m, then a 20 m GUIDED translation at the same altitude: truth altitude stays within
// +-0.15 m of the hover altitude all the way (WPNAV_SPEED 10 m/s, WPNAV_ACCEL 2.5 m/s^2: the carrot
// peaks at ~7 m/s; body-frame drag along the tilted thrust axis pulls down while cruising)
void horizontal_move_keeps_altitude(const char* world) {
  SCOPED_TRACE(world);
  auto sim = make_sim(world);
  take_off(*sim, 5.0);
  sim->run_until(sim->time_s() + 4.0);  // settle
  // the hover altitude: truth, averaged over 1 s (the hold itself wanders by a few cm)
  double z_sum = 0.0;
  int n = 0;
  const double avg_end = sim->time_s() + 1.0;
  while (sim->time_s() < avg_end) {
    sim->step();
    z_sum += sim->truth(0).position_enu_m.z();
    ++n;
  }
  const double hover_z = z_sum / n;
  const Eigen::Vector3d est = sim->fc(0).estimate().position_enu_m;
  const double target_z = sim->fc(0).home_enu_m().z() + 5.0;
  goto_enu(*sim, Eigen::Vector3d(est.x() + 20.0, est.y() - 5.0, target_z));
  double worst = 0.0;
  const double end = sim->time_s() + 20.0;
  while (sim->time_s() < end) {
    sim->step();
    const double dz = sim->truth(0).position_enu_m.z() - hover_z;
    if (std::abs(dz) > std::abs(worst)) worst = dz;
  }
  std::printf("[%s] 20 m level move: worst truth altitude error %+.3f m\n", world, worst);
  EXPECT_LT(std::abs(worst), kMoveAltTolM);
  EXPECT_NEAR(sim->fc(0).estimate().position_enu_m.x(), est.x() + 20.0, kSettleTolM);
}

TEST(Flight, HorizontalMoveKeepsAltitude) {
  horizontal_move_keeps_altitude("empty.xml");
  horizontal_move_keeps_altitude("hexa.xml");
}

TEST(Flight, GuidedGotoPassesWithin1mOfTheTarget) {
  auto sim = make_sim("empty.xml");
  take_off(*sim, 10.0);
  const Eigen::Vector3d target(-15.0, 25.0, 15.0);
  goto_enu(*sim, target);
  double closest = 1e9;
  const double end = sim->time_s() + 40.0;
  while (sim->time_s() < end) {
    sim->step();
    closest = std::min(closest, (sim->truth(0).position_enu_m - target).norm());
  }
  EXPECT_LT(closest, kPassTolM);
}

TEST(Flight, AutoMissionPassesWithin1mOfEveryWaypointThenLandsAndDisarms) {
  auto sim = make_sim("empty.xml");
  take_off(*sim, 10.0);
  const std::vector<Eigen::Vector3d> wps = {{15, 0, 10}, {15, 15, 12}, {0, 15, 10}};
  std::vector<fc::MissionItem> items(1);  // item 0: home
  for (const auto& p : wps) {
    fc::MissionItem it;
    it.kind = fc::MissionItem::Kind::kWaypoint;
    it.position_enu_m = p;
    items.push_back(it);
  }
  fc::MissionItem land;
  land.kind = fc::MissionItem::Kind::kLand;
  land.position_valid = false;
  items.push_back(land);
  sim->post(0, [items](fc::FlightController& f) {
    f.set_mission(items);
    EXPECT_EQ(f.set_mode(fc::Mode::kAuto), fc::CommandResult::kAccepted);
  });
  std::vector<double> closest(wps.size(), 1e9);
  std::vector<int> reached;
  const double end = sim->time_s() + 120.0;
  while (sim->time_s() < end && (sim->fc(0).armed() || sim->time_s() < 5.0)) {
    sim->step();
    for (size_t i = 0; i < wps.size(); ++i) {
      closest[i] = std::min(closest[i], (sim->truth(0).position_enu_m - wps[i]).norm());
    }
    for (int seq : sim->fc(0).drain_reached_items()) reached.push_back(seq);
  }
  for (size_t i = 0; i < wps.size(); ++i) EXPECT_LT(closest[i], kPassTolM) << "waypoint " << i + 1;
  EXPECT_GE(reached.size(), 3u);
  EXPECT_FALSE(sim->fc(0).armed()) << "did not land and disarm";
  EXPECT_LT(sim->truth(0).position_enu_m.z(), 0.3);
  EXPECT_EQ(sim->events().count(EventType::kCrash), 0u);
}

TEST(Flight, LandLandsAndDisarms) {
  auto sim = make_sim("empty.xml");
  take_off(*sim, 10.0);
  sim->post(0, [](fc::FlightController& f) { EXPECT_EQ(f.land(), fc::CommandResult::kAccepted); });
  const double end = sim->time_s() + 60.0;
  while (sim->time_s() < end && sim->fc(0).armed()) sim->step();
  EXPECT_FALSE(sim->fc(0).armed());
  EXPECT_LT(sim->truth(0).position_enu_m.z(), 0.3);
  EXPECT_EQ(sim->events().count(EventType::kCrash), 0u);
}

TEST(Flight, RtlReturnsHomeAndLands) {
  auto sim = make_sim("empty.xml");
  take_off(*sim, 10.0);
  const Eigen::Vector3d home = sim->fc(0).home_enu_m();
  goto_enu(*sim, Eigen::Vector3d(30, 10, 10));
  sim->run_until(sim->time_s() + 20.0);
  ASSERT_GT((sim->truth(0).position_enu_m - home).head<2>().norm(), 25.0);
  sim->post(0, [](fc::FlightController& f) { EXPECT_EQ(f.rtl(), fc::CommandResult::kAccepted); });
  const double end = sim->time_s() + 120.0;
  while (sim->time_s() < end && sim->fc(0).armed()) sim->step();
  EXPECT_FALSE(sim->fc(0).armed());
  EXPECT_LT((sim->truth(0).position_enu_m - home).head<2>().norm(), 1.0);
  EXPECT_LT(sim->truth(0).position_enu_m.z(), 0.3);
}

// a hexa that loses one rotor in flight still lands under control: the flight controller finds the
// lost rotor from the control response (it is never told), flies on the five others and gives up yaw
// (the hexa may turn slowly), then LAND brings it down and disarms without a hard landing
TEST(Flight, HexaWithOneDeadRotorStillLands) {
  auto sim = make_sim("hexa.xml");
  take_off(*sim, 10.0);
  sim->run_until(sim->time_s() + 2.0);
  sim->fc(0).drain_status_texts();
  sim->set_motor_failed(0, 0, true);
  sim->post(0, [](fc::FlightController& f) { f.land(); });
  const double failed_at = sim->time_s();
  double detected_at = -1.0;
  double max_sink = 0.0, max_yaw_rate = 0.0, max_tilt = 0.0, touchdown_speed = -1.0;
  const double end = sim->time_s() + 60.0;
  while (sim->time_s() < end && sim->fc(0).armed()) {
    sim->step();
    const fc::TruthState t = sim->truth(0);
    max_sink = std::max(max_sink, -t.velocity_enu_m_s.z());
    max_yaw_rate = std::max(max_yaw_rate, std::abs(t.rate_body_rad_s.z()));
    const Eigen::Vector3d z = t.q_enu_body * Eigen::Vector3d::UnitZ();
    max_tilt = std::max(max_tilt, std::acos(std::clamp(z.z(), -1.0, 1.0)));
    if (touchdown_speed < 0.0 && t.on_ground) touchdown_speed = t.velocity_enu_m_s.norm();
    for (const fc::StatusText& s : sim->fc(0).drain_status_texts()) {
      // the FC names the rotor it lost, numbered from 1 as ArduPilot's motors
      if (s.text.rfind("Thrust loss", 0) == 0 && detected_at < 0.0) {
        detected_at = sim->time_s();
        EXPECT_EQ(s.text, "Thrust loss: motor 1, yaw released");
      }
    }
  }
  ASSERT_GE(detected_at, 0.0) << "the loss was never detected";
  std::printf(
      "[hexa, rotor 0 dead] detected after %.3f s, max sink %.2f m/s, max |yaw rate| %.2f rad/s, "
      "max tilt %.1f deg, "
      "touchdown at %.2f m/s, disarmed %d\n",
      detected_at - failed_at, max_sink, max_yaw_rate, max_tilt * 180.0 / common::kPi,
      touchdown_speed, !sim->fc(0).armed());
  EXPECT_EQ(sim->events().count(EventType::kCrash), 0u);
  EXPECT_FALSE(sim->fc(0).armed()) << "did not land and disarm";
  EXPECT_LT(sim->truth(0).position_enu_m.z(), 0.5);
  EXPECT_LT(max_sink, kDeadRotorMaxSinkM_S);
  EXPECT_LT(max_tilt, kDeadRotorMaxTiltRad);
}

}  // namespace
}  // namespace uavsim::server::sim

