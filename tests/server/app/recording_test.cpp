// The recording's overlay source (app/recording.hpp): a person watching the video can tell which
// vehicle did what and where -- every event line of a pop, a landing on the target, a crash and a
// ground station's failover names its vehicle and carries its colour, and the pop, the landing and
// the crash leave a marker at the vehicle's place that stays.
#include "app/recording.hpp"

#include <gtest/gtest.h>

#include <memory>
#include <string>

#include "../api/call_op.hpp"
#include "physics/world.hpp"

namespace uavsim::server::app {
namespace {

struct Recorded {
  std::unique_ptr<sim::Simulation> s;
  objects::ObjectSet objects;
  std::unique_ptr<RunReporter> reporter;
  std::unique_ptr<api::OverlayOps> notes;
  std::function<render::OverlayInfo()> source;
};

Recorded mbzirc2020() {
  Recorded r;
  physics::ComposeOptions o;
  o.models_dir = UAVSIM_MODELS_DIR;
  r.s = std::make_unique<sim::Simulation>(
      physics::World::load(std::string(UAVSIM_MODELS_DIR) + "/worlds/mbzirc2020.xml", o),
      sim::SimConfig{});
  r.objects = objects::add_world_objects(*r.s);
  r.reporter = std::make_unique<RunReporter>(*r.s, nullptr, nullptr);
  r.notes = std::make_unique<api::OverlayOps>(*r.s);
  r.source = record_overlay_source(*r.s, r.objects, *r.reporter, *r.notes);
  return r;
}

const render::OverlayLine* line_with(const render::OverlayInfo& info, const std::string& text) {
  for (const render::OverlayLine& l : info.events) {
    if (l.text.find(text) != std::string::npos) return &l;
  }
  return nullptr;
}

TEST(RecordOverlay, EventLinesNameTheirVehicleAndMarkersStayWhereItHappened) {
  Recorded r = mbzirc2020();
  sim::Simulation& s = *r.s;
  s.run_until(0.5);
  const Eigen::Vector3d uav0 = s.truth(0).position_enu_m, uav1 = s.truth(1).position_enu_m;
  s.record(sim::EventType::kBalloonPopped, 0, "balloon2");
  s.record(sim::EventType::kLandedOnTarget, 1, "");
  s.record(sim::EventType::kCrash, 1, "hard landing");
  const nlohmann::json note = api::testing::call_op(
      *r.notes, "overlay_note", {{"text", "uav0 takes over the side of uav1"}, {"vehicle", "uav0"}});
  ASSERT_FALSE(note.contains("error")) << note;
  const render::OverlayInfo info = r.source();

  // every line names the vehicle and is drawn in its colour
  const render::OverlayLine* pop = line_with(info, "uav0 balloon_popped balloon2");
  const render::OverlayLine* landed = line_with(info, "uav1 landed_on_target");
  const render::OverlayLine* crash = line_with(info, "uav1 crash hard landing");
  const render::OverlayLine* failover = line_with(info, "uav0 takes over the side of uav1");
  ASSERT_TRUE(pop && landed && crash && failover);
  EXPECT_EQ(pop->vehicle, 0);
  EXPECT_EQ(landed->vehicle, 1);
  EXPECT_EQ(crash->vehicle, 1);
  EXPECT_EQ(failover->vehicle, 0);

  // the places: where each vehicle was
  ASSERT_EQ(info.markers.size(), 3u);
  EXPECT_EQ(info.markers[0].text, "uav0 pop 1");
  EXPECT_EQ(info.markers[0].vehicle, 0);
  EXPECT_TRUE(info.markers[0].position_enu_m.isApprox(uav0, 1e-9));
  EXPECT_EQ(info.markers[1].text, "uav1 landed");
  EXPECT_EQ(info.markers[2].text, "uav1 crash");
  EXPECT_TRUE(info.markers[2].position_enu_m.isApprox(uav1, 1e-9));

  // a killed vehicle's crash is the kill's: one marker
  s.record(sim::EventType::kVehicleKilled, 0, "test");
  s.record(sim::EventType::kCrash, 0, "killed: test");
  const render::OverlayInfo killed = r.source();
  ASSERT_EQ(killed.markers.size(), 4u);
  EXPECT_EQ(killed.markers[3].text, "uav0 killed");

  // 9 s later the lines are gone (shown 4 s), the markers stay, the trails hold 10 s
  s.run_until(9.5);
  const render::OverlayInfo later = r.source();
  EXPECT_TRUE(later.events.empty() || !line_with(later, "balloon_popped"));
  EXPECT_EQ(later.markers.size(), 4u);
  ASSERT_EQ(later.trails_enu_m.size(), 2u);
  EXPECT_EQ(later.trails_enu_m[0].size(), 3u);  // the frames at 0.5 s (twice) and 9.5 s
}

TEST(RecordOverlay, LaunchersCountersFollowTheServersOwn) {
  Recorded r = mbzirc2020();
  const nlohmann::json counter =
      api::testing::call_op(*r.notes, "overlay_counter", {{"name", "coverage"}, {"text", "coverage 62.0 %"}});
  ASSERT_FALSE(counter.contains("error")) << counter;
  const render::OverlayInfo info = r.source();
  ASSERT_EQ(info.counters.size(), 2u);
  EXPECT_EQ(info.counters[0], "balloons popped 0/5");
  EXPECT_EQ(info.counters[1], "coverage 62.0 %");
}

}  // namespace
}  // namespace uavsim::server::app
