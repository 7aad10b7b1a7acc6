// Obstacles block radio, on both backends (radio/sim_radio.hpp, physics/line_of_sight.hpp): two
// quads 40 m apart with a wall between them (tests/data/worlds/radio_wall.xml: geom group 3, 40
// dB). The link drops while the wall stands, and returns when it is moved away; with no loss
// configured the wall changes nothing.
#include <gtest/gtest.h>
#include <signal.h>

#include <memory>
#include <string>
#include <vector>

#include "physics/object_bodies.hpp"
#include "radio/sim_radio.hpp"
#include "sim/simulation.hpp"

namespace uavsim::server::radio {
namespace {

std::vector<Backend> backends() {
  std::vector<Backend> b{Backend::kSimple};
#ifdef UAVSIM_NS3_HELPER_PATH
  b.push_back(Backend::kNs3);
#endif
  return b;
}

class RadioObstacle : public ::testing::TestWithParam<Backend> {
 protected:
  void SetUp() override {
    physics::ComposeOptions o;
    o.models_dir = UAVSIM_MODELS_DIR;
    sim_ = std::make_unique<sim::Simulation>(
        physics::World::load(std::string(UAVSIM_TEST_DATA_DIR) + "/worlds/radio_wall.xml", o),
        sim::SimConfig{});
    BackendOptions backend;
    backend.backend = GetParam();
#ifdef UAVSIM_NS3_HELPER_PATH
    backend.ns3.helper_path = UAVSIM_NS3_HELPER_PATH;
#endif
    RadioConfig c;
    apply_world_radio_settings(sim_->world(), &backend, true, &c);
    // log-distance without shadowing: 40 m is 40 dB of path loss beyond 1 m (25 log10 40), inside
    // the 44.95 dB budget (0 dBm - 40.05 dB at 1 m against -85 dBm); 40 dB more is far outside it
    c.propagation = Propagation::kLogDistance;
    c.shadowing_sigma_db = 0.0;
    if (GetParam() == Backend::kNs3) {
      c.mac_header_bytes = 11;
      c.collisions = true;
    }
    radio_ = &SimRadio::attach(*sim_, c, backend);
  }

  // one broadcast from uav0 every 20 ms for 0.2 s: how many uav1 received
  uint64_t delivered_in_burst() {
    const uint64_t before = radio_->model().link(0, 1).delivered;
    const double end_s = sim_->time_s() + 0.2;
    int k = 0;
    while (sim_->time_s() < end_s) {
      if (k++ % 20 == 0) radio_->send(0, kBroadcast, std::vector<uint8_t>(30, 0x42));
      sim_->step();
    }
    return radio_->model().link(0, 1).delivered - before;
  }

  void move_wall_y(double y_m) {
    const int wall = sim_->world().body_id("wall");
    ASSERT_GE(wall, 0);
    ASSERT_TRUE(physics::set_mocap_pose(sim_->world(), wall, Eigen::Vector3d(20.0, y_m, 5.0),
                                        Eigen::Quaterniond::Identity()));
  }

  std::unique_ptr<sim::Simulation> sim_;
  SimRadio* radio_ = nullptr;
};

TEST_P(RadioObstacle, TheWallDropsTheLinkAndItReturnsWhenTheWallMoves) {
  EXPECT_EQ(radio_->model().config().obstacle_loss_db[3], 40.0);  // from the world
  EXPECT_EQ(delivered_in_burst(), 0u);
  EXPECT_GT(radio_->model().link(0, 1).out_of_range, 0u);
  // the wall 30 m aside: the path is clear again (the cached cast is at most 0.1 s old)
  move_wall_y(30.0);
  sim_->step();
  delivered_in_burst();  // the cache catches up within this burst
  EXPECT_EQ(delivered_in_burst(), 10u);
  // and back
  move_wall_y(0.0);
  sim_->step();
  delivered_in_burst();
  EXPECT_EQ(delivered_in_burst(), 0u);
}

TEST_P(RadioObstacle, WithoutALossForItsGroupTheWallChangesNothing) {
  RadioConfig c = radio_->model().config();
  c.obstacle_loss_db.fill(0.0);
  std::string why;
  ASSERT_TRUE(radio_->model().set_config(c, &why)) << why;
  EXPECT_EQ(delivered_in_burst(), 10u);
}

#ifdef UAVSIM_NS3_HELPER_PATH
TEST_P(RadioObstacle, AHelperThatDiesIsReportedOnceSoTheServerEndsTheRun) {
  if (GetParam() != Backend::kNs3) GTEST_SKIP() << "the simple backend has no helper";
  std::vector<std::string> reports;
  radio_->set_on_failure([&](const std::string& why) { reports.push_back(why); });
  auto* ns3 = dynamic_cast<Ns3Channel*>(&radio_->model());
  ASSERT_NE(ns3, nullptr);
  ASSERT_EQ(::kill(ns3->helper_pid(), SIGKILL), 0);
  radio_->send(0, kBroadcast, std::vector<uint8_t>(10, 1));
  for (int k = 0; k < 20; ++k) sim_->step();
  ASSERT_EQ(reports.size(), 1u);
  EXPECT_NE(reports[0].find("signal 9"), std::string::npos) << reports[0];
  EXPECT_TRUE(radio_->take_deliveries().empty());
}
#endif

INSTANTIATE_TEST_SUITE_P(Backends, RadioObstacle, ::testing::ValuesIn(backends()),
                         [](const auto& info) { return std::string(backend_name(info.param)); });

}  // namespace
}  // namespace uavsim::server::radio
