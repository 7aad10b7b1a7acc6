// The options the mission launchers share and the server they ask for (missions/common).
#include "uavsim/launch/run_options.hpp"

#include <gtest/gtest.h>

#include <string>
#include <utility>
#include <vector>

namespace {

using uavsim::launch::parse_run_option;
using uavsim::launch::run_server_spec;
using uavsim::launch::RunOptionParse;
using uavsim::launch::RunOptions;
using Args = std::vector<std::string>;

TEST(RunServerSpec, SeedThenTheMissionsArgumentsAndNothingUnasked) {
  RunOptions o;
  o.server = "/bin/uavsim-server";
  o.world = "w.xml";
  o.seed = 7;
  o.run_dir = "";  // none
  const auto spec = run_server_spec(o, {"--camera", "uav0_front:fps=15"});
  EXPECT_EQ(spec.path, "/bin/uavsim-server");
  EXPECT_EQ(spec.world, "w.xml");
  EXPECT_EQ(spec.extra_args, (Args{"--seed", "7", "--camera", "uav0_front:fps=15"}));
}

// the order every launcher passed them in: the video's, the log directory, the conditions
TEST(RunServerSpec, TheVideoTheRunDirectoryAndTheConditionsFollowInOrder) {
  RunOptions o;
  o.seed = 3;
  o.record = "d/video.mp4";
  o.run_dir = "d";
  o.realism = "field";
  o.wind = "3,90";
  EXPECT_EQ(
      run_server_spec(o, {}).extra_args,
      (Args{"--seed", "3", "--record", "d/video.mp4", "--record-camera", "follow",
            "--record-layout", "tiled", "--log-dir", "d", "--realism", "field", "--wind", "3,90"}));
}

// coverage-run films without a layout: the server's own default
TEST(RunServerSpec, AnEmptyLayoutIsNotPassed) {
  RunOptions o;
  o.record = "v.mp4";
  o.record_camera = "overview";
  o.record_layout = "";
  o.run_dir = "";
  EXPECT_EQ(
      run_server_spec(o, {"--no-cameras"}).extra_args,
      (Args{"--seed", "1", "--no-cameras", "--record", "v.mp4", "--record-camera", "overview"}));
}

TEST(ParseRunOption, TheSharedOptionsAreTaken) {
  RunOptions o;
  const std::pair<const char*, const char*> given[] = {
      {"--world", "w.xml"},
      {"--server", "/bin/s"},
      {"--record", "v.mp4"},
      {"--record-camera", "top"},
      {"--record-layout", "single"},
      {"--run-dir", "d"},
      {"--json", "s.json"},
      {"--events", "e.jsonl"},
      {"--realism", "ideal"},
      {"--wind", "3,90"},
      {"--seed", "42"},
      {"--truth-hz", "25"},
  };
  for (const auto& [name, value] : given)
    EXPECT_EQ(parse_run_option(name, value, &o), RunOptionParse::kTaken) << name;
  EXPECT_EQ(o.world, "w.xml");
  EXPECT_EQ(o.server, "/bin/s");
  EXPECT_EQ(o.record, "v.mp4");
  EXPECT_EQ(o.record_camera, "top");
  EXPECT_EQ(o.record_layout, "single");
  EXPECT_EQ(o.run_dir, "d");
  EXPECT_EQ(o.json_path, "s.json");
  EXPECT_EQ(o.events_path, "e.jsonl");
  EXPECT_EQ(o.realism, "ideal");
  EXPECT_EQ(o.wind, "3,90");
  EXPECT_EQ(o.seed, 42u);
  EXPECT_EQ(o.truth_hz, 25.0);
}

// the launchers' own options and flags are left to them
TEST(ParseRunOption, OthersAreNotCommon) {
  RunOptions o;
  EXPECT_EQ(parse_run_option("--budget", "60", &o), RunOptionParse::kNotCommon);
  EXPECT_EQ(parse_run_option("--quiet", "x", &o), RunOptionParse::kNotCommon);
  EXPECT_EQ(parse_run_option("--no-record", "x", &o), RunOptionParse::kNotCommon);
}

// a seed must be a whole number; ground truth from 0.01 to 1000 rows a second
TEST(ParseRunOption, UnusableNumbersAreBad) {
  RunOptions o;
  EXPECT_EQ(parse_run_option("--seed", "1.5", &o), RunOptionParse::kBad);
  EXPECT_EQ(parse_run_option("--seed", "-1", &o), RunOptionParse::kBad);
  EXPECT_EQ(parse_run_option("--truth-hz", "0", &o), RunOptionParse::kBad);
  EXPECT_EQ(parse_run_option("--truth-hz", "1001", &o), RunOptionParse::kBad);
  EXPECT_EQ(parse_run_option("--truth-hz", "ten", &o), RunOptionParse::kBad);
}

// the world file under the models directory's worlds/, and the built server when none is installed
TEST(DefaultWorldAndServer, TheWorldUnderModelsWorldsAndTheBuiltServer) {
  RunOptions o;
  uavsim::launch::default_world_and_server(&o, "w.xml", "/src/models",
                                           "/build/server/uavsim-server");
  const std::string tail = "/worlds/w.xml";
  ASSERT_GE(o.world.size(), tail.size());
  EXPECT_EQ(o.world.substr(o.world.size() - tail.size()), tail) << o.world;
  EXPECT_EQ(o.server, "/build/server/uavsim-server");
}

TEST(ResolveRunFiles, NoRunDirectoryAndNoRecordLeaveNoFiles) {
  RunOptions o;
  o.run_dir = "none";
  ASSERT_TRUE(uavsim::launch::resolve_run_files("test", &o, false));
  EXPECT_EQ(o.run_dir, "");
  EXPECT_EQ(o.record, "");
  EXPECT_EQ(o.json_path, "");
}

}  // namespace
