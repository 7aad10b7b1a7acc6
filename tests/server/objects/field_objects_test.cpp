// World objects under field conditions (sim/field_conditions.hpp): gimbal lag and slew limits,
// balloon heights drawn per seed, balloons swaying in the wind.
#include <gtest/gtest.h>
#include <mujoco/mujoco.h>

#include <cmath>

#include "objects/balloons.hpp"
#include "objects/gimbal.hpp"
#include "objects_fixture.hpp"
#include "uavsim/common/angles.hpp"

namespace uavsim::server::objects {
namespace {

constexpr double kAngleTol_rad = 1e-9;
// discrete first order against the continuous exp(-t / tau)
constexpr double kDecayRelTol = 0.02;
// the shipped gimbal's view pitch: level, after one time constant, after five
constexpr double kLevelTol_rad = 1e-6;
constexpr double kOneTauTol_rad = 0.03;
constexpr double kSettledTol_rad = 0.01;
// the balloon's lean in the wind, and its axis' tilt against that lean
constexpr double kLeanTol_m = 0.05;
constexpr double kLeanAxisTol = 0.01;

double angle_between(const Eigen::Quaterniond& a, const Eigen::Quaterniond& b) {
  return Eigen::AngleAxisd(a.conjugate() * b).angle();
}

TEST(GimbalDynamics, AttitudeStepGivesAPointingErrorThatDecaysWithTheTimeConstant) {
  // the camera rides on the body: a 0.3 rad step in body roll turns the camera with it; the loop
  // then slews back to the (earth-fixed) target: error(t) = 0.3 exp(-t / tau) without limits
  sim::GimbalDynamicsParams p;
  p.time_const_s = 0.05;
  constexpr double kDt = 0.001;
  constexpr double kStep_rad = 0.3;
  const Eigen::Quaterniond q_enu_target = Eigen::Quaterniond::Identity();
  GimbalMotion m;
  step_gimbal_motion(p, q_enu_target, kDt, &m);  // starts on target, body level
  const Eigen::Quaterniond q_enu_body(Eigen::AngleAxisd(kStep_rad, Eigen::Vector3d::UnitX()));
  const Eigen::Quaterniond q_body_target = q_enu_body.conjugate() * q_enu_target;
  EXPECT_NEAR(angle_between(q_enu_body * m.q_body_cam, q_enu_target), kStep_rad, kAngleTol_rad);
  for (double t = kDt; t <= 3.0 * p.time_const_s + 1e-9; t += kDt) {
    step_gimbal_motion(p, q_body_target, kDt, &m);
    const double err = angle_between(q_enu_body * m.q_body_cam, q_enu_target);
    // discrete first order: (1 - dt / tau)^k against exp(-k dt / tau): within 2 % over three tau
    EXPECT_NEAR(err, kStep_rad * std::exp(-t / p.time_const_s), kDecayRelTol * kStep_rad)
        << "t = " << t;
  }
}

TEST(GimbalDynamics, SlewRateAndAccelerationStayWithinTheirLimits) {
  sim::GimbalDynamicsParams p;
  p.time_const_s = 0.02;
  p.rate_max_rad_s = 1.0;
  p.accel_max_rad_s2 = 20.0;
  constexpr double kDt = 0.001;
  GimbalMotion m;
  step_gimbal_motion(p, Eigen::Quaterniond::Identity(), kDt, &m);
  const Eigen::Quaterniond target(Eigen::AngleAxisd(1.0, Eigen::Vector3d::UnitY()));
  double prev_rate = 0.0, max_rate = 0.0, max_accel = 0.0;
  double t_reach = -1.0;
  for (int k = 1; k <= 3000; ++k) {
    step_gimbal_motion(p, target, kDt, &m);
    const double rate = m.rate_body_rad_s.norm();
    max_rate = std::max(max_rate, rate);
    max_accel = std::max(max_accel, std::abs(rate - prev_rate) / kDt);
    prev_rate = rate;
    if (t_reach < 0 && angle_between(m.q_body_cam, target) < 0.01) t_reach = k * kDt;
  }
  EXPECT_LE(max_rate, p.rate_max_rad_s + 1e-9);
  EXPECT_LE(max_accel, p.accel_max_rad_s2 + 1e-6);
  // 1 rad at 1 rad/s, after 0.05 s of acceleration: a little over a second
  EXPECT_GT(t_reach, 1.0);
  EXPECT_LT(t_reach, 1.3);
}

TEST(GimbalDynamics, PerfectWithoutDynamics) {
  // the ideal world: no time constant, the camera is on target every step
  GimbalMotion m;
  const Eigen::Quaterniond a(Eigen::AngleAxisd(0.4, Eigen::Vector3d::UnitZ()));
  step_gimbal_motion(sim::GimbalDynamicsParams{}, Eigen::Quaterniond::Identity(), 0.001, &m);
  step_gimbal_motion(sim::GimbalDynamicsParams{}, a, 0.001, &m);
  EXPECT_LT(angle_between(m.q_body_cam, a), 1e-9);
}

std::unique_ptr<sim::Simulation> field_2020(uint64_t seed, const sim::FieldConditions& field) {
  physics::ComposeOptions o;
  o.models_dir = UAVSIM_MODELS_DIR;
  sim::SimConfig c;
  c.seed = seed;
  c.field = field;
  return std::make_unique<sim::Simulation>(
      physics::World::load(std::string(UAVSIM_MODELS_DIR) + "/worlds/mbzirc2020.xml", o), c);
}

TEST(GimbalDynamics, AFastManoeuvreTiltsTheViewForAMoment) {
  // mbzirc2020's forward camera with the field gimbal (50 ms): the vehicle snaps 0.3 rad nose down;
  // the camera first turns with it, then comes back level (the target) within a few time constants
  sim::FieldConditions field;
  field.gimbal.time_const_s = 0.05;
  auto sim = field_2020(1, field);
  const ObjectSet set = add_world_objects(*sim);
  const Gimbal& g = set.gimbals->gimbals()[0];
  const Eigen::Quaterniond level(Eigen::AngleAxisd(common::kPi / 2, Eigen::Vector3d::UnitZ()));
  physics::set_vehicle_state(sim->world(), 0, Eigen::Vector3d(-10, -27, 3), level,
                             Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero());
  for (int k = 0; k < 200; ++k) sim->step();
  auto pitch_of_view = [&] {
    const Eigen::Vector3d x =
        physics::body_orientation_enu(sim->world(), g.body_id) * Eigen::Vector3d::UnitX();
    return std::asin(std::clamp(x.z(), -1.0, 1.0));
  };
  EXPECT_NEAR(pitch_of_view(), 0.0, kLevelTol_rad);
  const Eigen::Quaterniond nose_down =
      level * Eigen::Quaterniond(Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitY()));
  auto hold = [&](int steps) {
    for (int k = 0; k < steps; ++k) {
      physics::set_vehicle_state(sim->world(), 0, Eigen::Vector3d(-10, -27, 3), nose_down,
                                 Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero());
      sim->step();
    }
  };
  hold(2);
  EXPECT_LT(pitch_of_view(), -0.25);  // tilted with the body
  hold(48);                           // 50 ms: one time constant
  EXPECT_NEAR(pitch_of_view(), -0.3 * std::exp(-1.0), kOneTauTol_rad);
  hold(200);  // 5 time constants
  EXPECT_NEAR(pitch_of_view(), 0.0, kSettledTol_rad);
}

TEST(GimbalDynamics, CapturesPlaceTheBodiesButNeverStepTheLoop) {
  // Two identical worlds with the field gimbal, the vehicle rocked nose up and down and the
  // pointing target changed after every capture; in b the capture-phase placement runs before every
  // step (as if every step took a snapshot). The stabilisation loop must not notice: same camera
  // orientation, bit for bit (a capture that stepped the loop would step it towards the old
  // target).
  sim::FieldConditions field;
  field.gimbal.time_const_s = 0.05;
  auto a = field_2020(1, field);
  auto b = field_2020(1, field);
  const ObjectSet sa = add_world_objects(*a), sb = add_world_objects(*b);
  const Eigen::Quaterniond level(Eigen::AngleAxisd(common::kPi / 2, Eigen::Vector3d::UnitZ()));
  for (int k = 0; k < 300; ++k) {
    const double pitch_rad = 0.3 * std::sin(k * 0.05);
    const Eigen::Quaterniond q =
        level * Eigen::Quaterniond(Eigen::AngleAxisd(pitch_rad, Eigen::Vector3d::UnitY()));
    const Eigen::Vector3d p(-10 + 0.01 * k, -27, 3);
    for (sim::Simulation* s : {a.get(), b.get()}) {
      physics::set_vehicle_state(s->world(), 0, p, q, Eigen::Vector3d::Zero(),
                                 Eigen::Vector3d::Zero());
    }
    sb.gimbals->place(*b);
    // placed (the mocap pose a snapshot copies) at the vehicle's pose of this instant: the mount
    // under the hull of the vehicle just moved
    const Gimbal& gb = sb.gimbals->gimbals()[0];
    const int mocap = physics::mocap_index(b->world(), gb.body_id);
    ASSERT_GE(mocap, 0);
    const Eigen::Vector3d placed_m =
        Eigen::Map<const Eigen::Vector3d>(b->world().data()->mocap_pos + 3 * mocap);
    EXPECT_LT((placed_m - (p + q * gb.mount_body_m)).norm(), 1e-9);
    // a pointing command arrives after the capture (post-control), in both worlds
    for (const ObjectSet* set : {&sa, &sb}) {
      Gimbal& g = set->gimbals->gimbals()[0];
      g.mode = GimbalMode::kTargets;
      g.pitch_rad = -0.2 * (k % 7);
    }
    a->step();
    b->step();
  }
  const Gimbal& ga = sa.gimbals->gimbals()[0];
  const Gimbal& gb = sb.gimbals->gimbals()[0];
  EXPECT_EQ(ga.motion.q_body_cam.coeffs(), gb.motion.q_body_cam.coeffs());
  EXPECT_EQ(ga.motion.rate_body_rad_s, gb.motion.rate_body_rad_s);
  EXPECT_GT(ga.motion.rate_body_rad_s.norm(),
            0.0);  // the loop was slewing: the comparison means something
  // and the schedule places them first in the capture phase, before any snapshot
  const auto names = a->schedule().names(sim::Phase::kCapture);
  ASSERT_FALSE(names.empty());
  EXPECT_EQ(names.front(), "gimbals.pose");
}

TEST(FieldBalloons, HeightsComeFromTheSeedWithinTheSpreadAndPositionsStay) {
  sim::FieldConditions field;
  field.balloons.height_spread_m = 0.5;
  bool varied = false;
  for (uint64_t seed = 1; seed <= 10; ++seed) {
    auto ideal = testing::make_shipped("mbzirc2020.xml", seed);
    auto a = field_2020(seed, field);
    auto b = field_2020(seed, field);
    const ObjectSet si = add_world_objects(*ideal), sa = add_world_objects(*a),
                    sb = add_world_objects(*b);
    for (size_t i = 0; i < sa.balloons->balloons().size(); ++i) {
      const BalloonState& x = sa.balloons->balloons()[i];
      // top within 3.0 +- 0.5 m, the same ground position as without variation, the same per seed
      const double top = x.position_enu_m.z() + x.radius_m;
      EXPECT_GE(top, 2.5);
      EXPECT_LE(top, 3.5);
      varied = varied || std::abs(top - 3.0) > 0.05;
      EXPECT_EQ(x.position_enu_m.head<2>(), si.balloons->balloons()[i].position_enu_m.head<2>());
      EXPECT_EQ(x.position_enu_m, sb.balloons->balloons()[i].position_enu_m);
    }
  }
  EXPECT_TRUE(varied);
}

TEST(FieldBalloons, BalloonsLeanDownwindAndSway) {
  // 5 m/s from the west: the balloons lean east; the pole is sized for 0.25 m at the top in 5 m/s
  // (balloons.cpp), i.e. about 0.25 * 2.7 / 3.0 = 0.23 m at the balloon's centre
  sim::FieldConditions field;
  field.balloons.sway = true;
  field.wind.speed_m_s = 5.0;
  field.wind.from_deg = 270.0;
  auto sim = field_2020(1, field);
  const ObjectSet set = add_world_objects(*sim);
  const Eigen::Vector3d start = set.balloons->balloons()[0].position_enu_m;
  double min_dx = 1e9, max_dx = -1e9;
  sim->run_until(3.0);
  for (int k = 0; k < 2000; ++k) {
    sim->step();
    const double dx = set.balloons->balloons()[0].position_enu_m.x() - start.x();
    min_dx = std::min(min_dx, dx);
    max_dx = std::max(max_dx, dx);
  }
  const double lean_m = 0.5 * (min_dx + max_dx);
  EXPECT_NEAR(lean_m, 0.23, kLeanTol_m);
  // settled (the damping takes the first swing out in a few seconds)
  EXPECT_LT(max_dx - min_dx, 0.02);
  // the body (pole and balloon) leans east about its foot: its z axis has a positive x component
  const int body = sim->world().body_id(set.balloons->balloons()[0].name);
  const mjtNum* q = sim->world().data()->xquat + 4 * body;  // w x y z
  EXPECT_NEAR(2.0 * (q[1] * q[3] + q[0] * q[2]), lean_m / 2.7, kLeanAxisTol);

  // turbulence makes them sway
  field.wind.turbulence_sd_m_s = 1.5;
  auto gusty = field_2020(1, field);
  const ObjectSet gset = add_world_objects(*gusty);
  gusty->run_until(3.0);
  double lo = 1e9, hi = -1e9;
  for (int k = 0; k < 20000; ++k) {
    gusty->step();
    const double dx = gset.balloons->balloons()[0].position_enu_m.x() - start.x();
    lo = std::min(lo, dx);
    hi = std::max(hi, dx);
  }
  EXPECT_GT(hi - lo, 0.05);
}

TEST(FieldBalloons, ThePoleStillMeetsTheGroundAndTouchesNothing) {
  sim::FieldConditions field;
  field.balloons.height_spread_m = 0.5;
  auto sim = field_2020(2, field);
  const ObjectSet set = add_world_objects(*sim);
  sim->run_until(0.5);
  // no contact involves a balloon body: the pole's underground part does not touch the ground plane
  // (mocap and world bodies do not collide), so the ideal world's contacts are as before
  const mjModel* m = sim->world().model();
  const mjData* d = sim->world().data();
  for (int i = 0; i < d->ncon; ++i) {
    for (const BalloonState& b : set.balloons->balloons()) {
      const int body = sim->world().body_id(b.name);
      EXPECT_NE(m->geom_bodyid[d->contact[i].geom1], body);
      EXPECT_NE(m->geom_bodyid[d->contact[i].geom2], body);
    }
  }
}

}  // namespace
}  // namespace uavsim::server::objects
