// Every shipped model loads and steps: vehicle and object templates on their own (plain MuJoCo), and
// every world through the composer.
#include <gtest/gtest.h>
#include <mujoco/mujoco.h>

#include <cmath>
#include <filesystem>

#include "physics/world.hpp"

namespace uavsim::server::physics {
namespace {

namespace fs = std::filesystem;

TEST(ModelsSmoke, EveryTemplateLoadsInPlainMujocoAndSteps) {
  int count = 0;
  for (const char* dir : {"vehicles", "objects"}) {
    const fs::path p = fs::path(UAVSIM_MODELS_DIR) / dir;
    if (!fs::is_directory(p)) continue;
    for (const auto& f : fs::directory_iterator(p)) {
      if (f.path().extension() != ".xml") continue;
      char error[1000] = "";
      mjModel* m = mj_loadXML(f.path().c_str(), nullptr, error, sizeof(error));
      ASSERT_NE(m, nullptr) << f.path() << ": " << error;
      mjData* d = mj_makeData(m);
      for (int i = 0; i < 100; ++i) mj_step(m, d);
      for (int i = 0; i < m->nq; ++i) EXPECT_TRUE(std::isfinite(d->qpos[i])) << f.path();
      mj_deleteData(d);
      mj_deleteModel(m);
      ++count;
    }
  }
  EXPECT_GE(count, 2);
}

TEST(ModelsSmoke, EveryWorldComposesLoadsAndSteps) {
  int count = 0;
  for (const auto& f : fs::directory_iterator(fs::path(UAVSIM_MODELS_DIR) / "worlds")) {
    if (f.path().extension() != ".xml") continue;
    // the 1000-quad scale world loads for seconds: its own scenario test flies it (sim_scale_tests)
    if (f.path().filename() == "grid1000.xml") continue;
    ComposeOptions o;
    o.models_dir = UAVSIM_MODELS_DIR;
    auto world = World::load(f.path().string(), o);
    EXPECT_GE(world->vehicles().size(), 1u) << f.path();
    for (int i = 0; i < 100; ++i) world->step();
    for (size_t v = 0; v < world->vehicles().size(); ++v) {
      EXPECT_TRUE(world->truth(v).position_enu_m.allFinite()) << f.path();
    }
    ++count;
  }
  EXPECT_GE(count, 3);
}

}  // namespace
}  // namespace uavsim::server::physics
