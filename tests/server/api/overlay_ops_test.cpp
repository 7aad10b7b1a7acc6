// The video overlay's ops (overlay_ops.hpp): counters replace each other by name and are bounded,
// notes carry the sim time and the vehicle, and every text is checked at the edge.
#include "api/overlay_ops.hpp"

#include <gtest/gtest.h>

#include <memory>
#include <string>

#include "physics/world.hpp"
#include "call_op.hpp"

namespace uavsim::server::api {
namespace {

using Json = nlohmann::json;

std::unique_ptr<sim::Simulation> two_quads() {
  physics::ComposeOptions o;
  o.models_dir = UAVSIM_MODELS_DIR;
  return std::make_unique<sim::Simulation>(
      physics::World::load(std::string(UAVSIM_MODELS_DIR) + "/worlds/mbzirc2020.xml", o),
      sim::SimConfig{});
}

// the result, or {"error": code}
Json call(OverlayOps& ops, const std::string& op, const Json& request) {
  return testing::call_op(ops, op, request);
}

TEST(OverlayOps, CountersAreReplacedByNameAndRemovedByEmptyText) {
  auto sim = two_quads();
  OverlayOps ops(*sim);
  EXPECT_EQ(
      call(ops, "overlay_counter", {{"name", "coverage"}, {"text", "coverage 10.0 %"}})["counters"],
      1);
  EXPECT_EQ(
      call(ops, "overlay_counter", {{"name", "coverage"}, {"text", "coverage 62.5 %"}})["counters"],
      1);
  EXPECT_EQ(call(ops, "overlay_counter", {{"name", "agents"}, {"text", "agents 4/5"}})["counters"],
            2);
  // in name order
  EXPECT_EQ(ops.counters(), (std::vector<std::string>{"agents 4/5", "coverage 62.5 %"}));
  EXPECT_EQ(call(ops, "overlay_counter", {{"name", "agents"}, {"text", ""}})["counters"], 1);
  EXPECT_EQ(ops.counters(), (std::vector<std::string>{"coverage 62.5 %"}));
}

TEST(OverlayOps, CountersAreBounded) {
  auto sim = two_quads();
  OverlayOps ops(*sim);
  for (size_t i = 0; i < kMaxOverlayCounters; ++i) {
    EXPECT_FALSE(call(ops, "overlay_counter", {{"name", "c" + std::to_string(i)}, {"text", "x"}})
                     .contains("error"));
  }
  EXPECT_EQ(call(ops, "overlay_counter", {{"name", "one_more"}, {"text", "x"}})["error"],
            "bad_field");
  // an existing one may still change
  EXPECT_FALSE(call(ops, "overlay_counter", {{"name", "c0"}, {"text", "y"}}).contains("error"));
}

TEST(OverlayOps, NotesCarryTheSimTimeAndTheVehicleAndTheNewestAreKept) {
  auto sim = two_quads();
  OverlayOps ops(*sim);
  EXPECT_DOUBLE_EQ(
      call(ops, "overlay_note",
           {{"text", "uav0 takes over the side of uav1"}, {"vehicle", "uav0"}})["time_s"],
      0.0);
  ASSERT_EQ(ops.notes().size(), 1u);
  EXPECT_EQ(ops.notes()[0].vehicle, 0);
  EXPECT_EQ(call(ops, "overlay_note", {{"text", "x"}, {"vehicle", "uav9"}})["error"],
            "unknown_vehicle");
  for (size_t i = 0; i < kMaxOverlayNotes + 3; ++i)
    call(ops, "overlay_note", {{"text", std::to_string(i)}});
  EXPECT_EQ(ops.notes().size(), kMaxOverlayNotes);
  EXPECT_EQ(ops.notes().back().text, std::to_string(kMaxOverlayNotes + 2));
  EXPECT_EQ(ops.notes().back().vehicle, -1);
}

TEST(OverlayOps, TextsAreCheckedAtTheEdge) {
  auto sim = two_quads();
  OverlayOps ops(*sim);
  EXPECT_EQ(call(ops, "overlay_note", Json::object())["error"], "missing_field");
  // a field of another type is bad_field (docs/protocol.md), refused before the op runs
  EXPECT_EQ(call(ops, "overlay_note", {{"text", 3}})["error"], "bad_field");
  EXPECT_EQ(
      call(ops, "overlay_note", {{"text", std::string(kMaxOverlayTextBytes + 1, 'a')}})["error"],
      "bad_field");
  EXPECT_EQ(call(ops, "overlay_note", {{"text", "line\nbreak"}})["error"], "bad_field");
  EXPECT_EQ(call(ops, "overlay_note", {{"text", "caf\xc3\xa9"}})["error"], "bad_field");
  EXPECT_EQ(call(ops, "overlay_counter", {{"text", "x"}})["error"], "bad_field");
  EXPECT_EQ(call(ops, "overlay_counter", {{"name", ""}, {"text", "x"}})["error"], "bad_field");
  EXPECT_TRUE(ops.notes().empty());
  EXPECT_TRUE(ops.counters().empty());
}

}  // namespace
}  // namespace uavsim::server::api
