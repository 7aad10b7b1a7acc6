// A world loaded without its vehicles' visual-only geoms (ComposeOptions::vehicle_visual_geoms off,
// what the server does when nothing can render): the same bodies, masses and contacts, the same
// flight to the bit, and the same radio line of sight as the full world.
#include <gtest/gtest.h>
#include <mujoco/mujoco.h>

#include <algorithm>
#include <array>
#include <memory>
#include <string>

#include "airframe/airframe.hpp"
#include "physics/line_of_sight.hpp"
#include "physics/world.hpp"
#include "physics/world_composer.hpp"
#include "test_worlds.hpp"

namespace uavsim::server::physics {
namespace {

std::string write_world(const std::string& name, const std::string& worldbody) {
  return testing::write_world("uavsim_visual_geoms_test", name, worldbody);
}

std::unique_ptr<World> load(const std::string& path, bool visual_geoms) {
  ComposeOptions o = testing::source_models();
  o.vehicle_visual_geoms = visual_geoms;
  return World::load(path, o);
}

// three quads in a row, 3 m apart, the full collision set (hull, gear, cutter blades)
const std::string kRow = R"(<uavsim_grid type="quad" prefix="uav" rows="1" cols="3" spacing="3"/>)";
// the same with the lean collision set: hull and gear collide, rotors are only drawn
const std::string kLeanRow =
    R"(<uavsim_grid type="quad" prefix="uav" rows="1" cols="3" spacing="3" collision="lean"/>)";

TEST(VisualGeoms, LeftOutTheyLeaveEveryBodyItsMassAndEveryGeomThatCollides) {
  const std::string path = write_world("row.xml", kRow);
  const auto full = load(path, true);
  const auto lean = load(path, false);
  const mjModel* f = full->model();
  const mjModel* l = lean->model();
  ASSERT_EQ(f->nbody, l->nbody);
  ASSERT_EQ(f->nq, l->nq);
  for (int b = 0; b < f->nbody; ++b) {
    EXPECT_EQ(f->body_mass[b], l->body_mass[b]) << b;
    for (int k = 0; k < 3; ++k) EXPECT_EQ(f->body_inertia[3 * b + k], l->body_inertia[3 * b + k]);
  }
  // the full quad: hull, 2 gear skids, 5 cutter blades collide; everything else is only drawn
  int colliding = 0;
  for (int g = 0; g < f->ngeom; ++g) colliding += full->vehicle_visual_only(g) ? 0 : 1;
  EXPECT_LT(l->ngeom, f->ngeom);
  EXPECT_EQ(l->ngeom, colliding);
  for (int g = 0; g < l->ngeom; ++g) EXPECT_FALSE(lean->vehicle_visual_only(g)) << g;
  // the full quad's rotors collide (a prop strike is a crash); its arms and struts are only drawn
  for (const char* name : {"uav1/hull", "uav1/gear_left", "uav1/blade2", "uav1/prop0"}) {
    EXPECT_GE(mj_name2id(l, mjOBJ_GEOM, name), 0) << name;
  }
  for (const char* name : {"uav1/arm0", "uav1/gear_strut0"}) {
    EXPECT_GE(mj_name2id(f, mjOBJ_GEOM, name), 0) << name;
    EXPECT_LT(mj_name2id(l, mjOBJ_GEOM, name), 0) << name;
  }
  // a lean quad keeps 3 of its 20 (hull and gear), as in a physics shard
  const auto lean_set = load(write_world("lean.xml", kLeanRow), false);
  EXPECT_EQ(lean_set->model()->ngeom, 1 + 3 * 3);
  EXPECT_EQ(load(write_world("lean.xml", kLeanRow), true)->model()->ngeom, 1 + 3 * 20);
}

TEST(VisualGeoms, AWorldWithoutThemFliesAndLandsBitForBitAsTheFullOne) {
  const std::string path = write_world("row.xml", kRow);
  const auto full = load(path, true);
  const auto lean = load(path, false);
  for (World* w : {full.get(), lean.get()}) {
    for (size_t v = 0; v < w->vehicles().size(); ++v) w->wake(v);
  }
  // each quad climbs on a thrust above its weight with a yaw and roll torque of its own, then falls
  // and lands on its gear, tilted: free flight, then contacts with the ground
  double highest_m = 0.0;
  for (int step = 0; step < 2500; ++step) {
    highest_m = std::max(highest_m, full->truth(0).position_enu_m.z());
    for (World* w : {full.get(), lean.get()}) {
      for (size_t v = 0; v < w->vehicles().size(); ++v) {
        airframe::Wrench wrench;
        if (step < 1000) {
          const double weight_n = w->vehicles()[v].airframe.mass_kg * 9.81;
          wrench.force_enu_n = Eigen::Vector3d(0.0, 0.0, 1.3 * weight_n);
          wrench.torque_body_nm = Eigen::Vector3d(0.002 * static_cast<double>(v), 0.0, 0.01);
        }
        w->apply_wrench(v, wrench);
      }
      w->step();
    }
  }
  for (size_t v = 0; v < full->vehicles().size(); ++v) {
    const airframe::TruthState a = full->truth(v);
    const airframe::TruthState b = lean->truth(v);
    for (int k = 0; k < 3; ++k) {
      EXPECT_EQ(a.position_enu_m[k], b.position_enu_m[k]) << "vehicle " << v << " axis " << k;
      EXPECT_EQ(a.velocity_enu_m_s[k], b.velocity_enu_m_s[k]) << "vehicle " << v;
    }
    EXPECT_EQ(a.q_enu_body.coeffs(), b.q_enu_body.coeffs()) << "vehicle " << v;
    EXPECT_EQ(a.on_ground, b.on_ground);
    EXPECT_TRUE(a.on_ground) << "vehicle " << v;  // back on the ground
  }
  EXPECT_GT(highest_m, 1.5);  // after a flight
}

// uav0 and uav2 10 m up (their body origins, the antennas, 0.16 m higher: the template's origin
// stands on its gear), 6 m apart on y = 0; uav1 between them, with collision set `collision`,
// placed so that the line between the antennas crosses one of its rotor discs or its hull
std::array<double, kGeomGroupCount> every_group_blocks() {
  std::array<double, kGeomGroupCount> loss{};
  loss.fill(30.0);
  return loss;
}

std::string three_quads(double uav1_y_m, double uav1_z_m, const std::string& collision) {
  return R"(<uavsim_vehicle type="quad" name="uav0" pos="0 0 10"/>
    <uavsim_vehicle type="quad" name="uav1" collision=")" +
         collision + R"(" pos="3 )" + std::to_string(uav1_y_m) + " " + std::to_string(uav1_z_m) +
         R"("/>
    <uavsim_vehicle type="quad" name="uav2" pos="6 0 10"/>)";
}

double loss_through_uav1(double uav1_y_m, double uav1_z_m, const std::string& collision,
                         bool visual_geoms) {
  const auto world =
      load(write_world("three.xml", three_quads(uav1_y_m, uav1_z_m, collision)), visual_geoms);
  mj_forward(world->model(), world->data());
  const LineOfSight sight(*world);
  return sight.blocked_loss_db(world->truth(0).position_enu_m, world->truth(2).position_enu_m, 0, 2,
                               every_group_blocks());
}

// rotor 0 sits at (0.1945, -0.1945, 0.045) in the quad's frame, a disc of radius 0.127: with the
// quad 0.1945 m to the side and 0.045 m down, the line crosses that disc (and rotor 3's) and misses
// the hull (0.08 m half-width), arms, gear and cutter
constexpr double kRotorY_m = 0.1945;
constexpr double kRotorZ_m = 10.0 - 0.045;

TEST(VisualGeoms, AVehicleBlocksRadioWithWhatItCollidesWithNotWithWhatIsOnlyDrawn) {
  for (bool visual : {true, false}) {
    SCOPED_TRACE(visual ? "full world" : "without visual-only geoms");
    // lean: the rotors are only drawn, and let the radio through
    EXPECT_EQ(loss_through_uav1(kRotorY_m, kRotorZ_m, "lean", visual), 0.0);
    // full: the rotors collide (a prop strike), and block
    EXPECT_EQ(loss_through_uav1(kRotorY_m, kRotorZ_m, "full", visual), 30.0);
    EXPECT_EQ(loss_through_uav1(0.0, 10.0, "lean", visual), 30.0);  // through the hull
    EXPECT_EQ(loss_through_uav1(2.0, 10.0, "lean", visual), 0.0);   // clear of it
  }
}

TEST(VisualGeoms, TheRotorDiscOfTheTestIsReallyOnTheLine) {
  // the test above would pass for nothing if the line missed the lean quad's rotors: cast it
  const auto world =
      load(write_world("probe.xml", three_quads(kRotorY_m, kRotorZ_m, "lean")), true);
  const mjModel* m = world->model();
  mjData* d = world->data();
  mj_forward(m, d);
  const mjtNum from[3] = {0.5, 0.0, world->truth(0).position_enu_m.z()};  // past uav0's rotors
  const mjtNum dir[3] = {1.0, 0.0, 0.0};
  int geom = -1;
  const mjtNum x = mj_ray(m, d, from, dir, nullptr, 1, -1, &geom);
  ASSERT_GE(geom, 0);
  EXPECT_LT(x, 3.0);
  // (rotors 0 and 3 both sit on it; 3 comes first)
  EXPECT_EQ(std::string(mj_id2name(m, mjOBJ_GEOM, geom)).rfind("uav1/prop", 0), 0u);
  EXPECT_TRUE(world->vehicle_visual_only(geom));
}

}  // namespace
}  // namespace uavsim::server::physics
