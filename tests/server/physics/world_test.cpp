#include "physics/world.hpp"

#include <gtest/gtest.h>
#include <mujoco/mujoco.h>

#include <cmath>
#include <string>
#include <vector>

namespace uavsim::server::physics {
namespace {

constexpr double kTol = 1e-9;
// the shipped airframe's thrust-to-weight ratio, quoted to two digits
constexpr double kThrustToWeightTol = 0.01;

// one free body whose centre of mass is off its origin, rotated, with four rotors and drag
constexpr const char* kOffsetQuad = R"(
<mujoco>
  <size nuser_site="5"/>
  <worldbody>
    <body name="v" pos="1 2 3" quat="0.9 0.1 -0.2 0.3">
      <freejoint/>
      <inertial pos="0.05 0.02 -0.03" mass="1.5" diaginertia="0.03 0.04 0.05"/>
      <geom name="hull" type="box" size="0.1 0.1 0.03" contype="0" conaffinity="0"/>
      <site name="v/rotor0" pos=" 0.2 -0.2 0.04" user=" 1 8 0.016 0.03 0.25"/>
      <site name="v/rotor1" pos="-0.2  0.2 0.04" user=" 1 8 0.016 0.03 0.25"/>
      <site name="v/rotor2" pos=" 0.2  0.2 0.04" user="-1 8 0.016 0.03 0.25"/>
      <site name="v/rotor3" pos="-0.2 -0.2 0.04" user="-1 8 0.016 0.03 0.25"/>
    </body>
  </worldbody>
  <custom>
    <text name="uavsim:vehicle:v" data="quad"/>
    <numeric name="uavsim:v:drag_lin" data="0.1 0.2 0.3"/>
    <numeric name="uavsim:v:drag_quad" data="0.05 0.06 0.07"/>
  </custom>
</mujoco>)";

TEST(World, FindsVehicleRotorsAndParametersFromMjcf) {
  auto world = World::from_mjcf(kOffsetQuad, "inline");
  ASSERT_EQ(world->vehicles().size(), 1u);
  const auto& a = world->vehicles()[0].airframe;
  EXPECT_EQ(a.frame, "quad");
  EXPECT_NEAR(a.mass_kg, 1.5, kTol);
  ASSERT_EQ(a.rotors.size(), 4u);
  EXPECT_EQ(a.rotors[2].spin_dir, -1);
  EXPECT_NEAR(a.rotors[1].position_body_m.y(), 0.2, kTol);
  EXPECT_NEAR(a.drag_quad_n_per_m2_s2.z(), 0.07, kTol);
  EXPECT_NEAR(a.com_body_m.x(), 0.05, kTol);
}

// The wrench written into the free joint's dofs equals what mj_applyFT computes for the same rotor
// forces applied at the rotor sites, reaction torques, and drag applied at the centre of mass.
TEST(World, QfrcAppliedWrenchEqualsMjApplyFT) {
  auto world = World::from_mjcf(kOffsetQuad, "inline");
  const mjModel* m = world->model();
  mjData* d = world->data();
  // give the body a velocity so drag is non-zero
  d->qvel[0] = 3.0;
  d->qvel[1] = -2.0;
  d->qvel[2] = 1.0;
  mj_forward(m, d);

  const auto& a = world->vehicles()[0].airframe;
  const double thrust[4] = {5.0, 6.0, 7.0, 4.0};
  const auto truth = world->truth(0);
  const airframe::Wrench w =
      airframe::compute_wrench(a, thrust, truth.q_enu_body, truth.velocity_enu_m_s);
  world->apply_wrench(0, w);
  std::vector<double> ours(d->qfrc_applied, d->qfrc_applied + m->nv);

  // the same physics through mj_applyFT
  std::vector<mjtNum> ref(m->nv, 0.0);
  const int body = world->vehicles()[0].body_id;
  const Eigen::Matrix3d R = truth.q_enu_body.toRotationMatrix();
  const Eigen::Vector3d origin(d->xpos + 3 * body);
  const Eigen::Vector3d zero = Eigen::Vector3d::Zero();
  for (int k = 0; k < 4; ++k) {
    const Eigen::Vector3d f = R * Eigen::Vector3d(0, 0, thrust[k]);
    const Eigen::Vector3d p = origin + R * a.rotors[k].position_body_m;
    const Eigen::Vector3d tau =
        R * Eigen::Vector3d(0, 0, -a.rotors[k].spin_dir * a.rotors[k].torque_coef_m * thrust[k]);
    mj_applyFT(m, d, f.data(), zero.data(), p.data(), body, ref.data());
    mj_applyFT(m, d, zero.data(), tau.data(), p.data(), body, ref.data());
  }
  const Eigen::Vector3d v_body = R.transpose() * truth.velocity_enu_m_s;
  const Eigen::Vector3d drag_body =
      -(a.drag_lin_n_per_m_s.cwiseProduct(v_body) +
        a.drag_quad_n_per_m2_s2.cwiseProduct(v_body.cwiseAbs().cwiseProduct(v_body)));
  const Eigen::Vector3d drag_enu = R * drag_body;
  const Eigen::Vector3d com(d->xipos + 3 * body);
  mj_applyFT(m, d, drag_enu.data(), zero.data(), com.data(), body, ref.data());

  for (int i = 0; i < m->nv; ++i) EXPECT_NEAR(ours[i], ref[i], kTol) << "dof " << i;
}

TEST(World, MissingFreeJointIsAStartupError) {
  const std::string bad = R"(<mujoco><worldbody><body name="v"><geom size="0.1"/></body></worldbody>
    <custom><text name="uavsim:vehicle:v" data="quad"/></custom></mujoco>)";
  EXPECT_THROW(World::from_mjcf(bad, "inline"), WorldError);
}

TEST(World, TooFewRotorsIsAStartupError) {
  const std::string bad = R"(<mujoco><worldbody><body name="v"><freejoint/><geom size="0.1"/></body>
    </worldbody><custom><text name="uavsim:vehicle:v" data="quad"/></custom></mujoco>)";
  try {
    World::from_mjcf(bad, "inline");
    FAIL();
  } catch (const WorldError& e) {
    EXPECT_NE(std::string(e.what()).find("rotor"), std::string::npos) << e.what();
  }
}

TEST(World, ShippedQuadHasDocumentedParameters) {
  ComposeOptions o;
  o.models_dir = UAVSIM_MODELS_DIR;
  auto world = World::load(std::string(UAVSIM_MODELS_DIR) + "/worlds/empty.xml", o);
  const auto& a = world->vehicles()[0].airframe;
  EXPECT_NEAR(a.mass_kg, 1.5, kTol);
  // max thrust about 2x weight: 29.44 N vs 2 * 1.5 * 9.81 = 29.43 N
  EXPECT_NEAR(a.max_total_thrust_n() / (a.mass_kg * 9.81), 2.0, kThrustToWeightTol);
}

TEST(World, RestingVehicleTouchesGroundOnlyWithLandingGear) {
  ComposeOptions o;
  o.models_dir = UAVSIM_MODELS_DIR;
  for (const char* w : {"/worlds/empty.xml", "/worlds/hexa.xml"}) {
    auto world = World::load(std::string(UAVSIM_MODELS_DIR) + w, o);
    world->wake(0);  // it starts parked (no contacts at all): standing on its own gear instead
    for (int i = 0; i < 500; ++i) world->step();
    std::vector<VehicleContact> contacts;
    world->vehicle_contacts(&contacts);
    ASSERT_FALSE(contacts.empty()) << w;
    for (const auto& c : contacts) {
      EXPECT_TRUE(c.landing_gear) << w << ": " << world->geom_name(c.geom);
      EXPECT_EQ(c.other_vehicle, -1);
    }
    // resting: no drift
    EXPECT_LT(world->truth(0).velocity_enu_m_s.norm(), 0.01) << w;
  }
}

}  // namespace
}  // namespace uavsim::server::physics
