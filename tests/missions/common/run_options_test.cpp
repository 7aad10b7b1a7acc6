// The options the mission launchers share and the server they ask for (missions/common).
#include "uavsim/launch/run_options.hpp"

#include <gtest/gtest.h>

#include <string>
#include <vector>

namespace {

using uavsim::launch::run_server_spec;
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

TEST(ResolveRunFiles, NoRunDirectoryAndNoRecordLeaveNoFiles) {
  RunOptions o;
  o.run_dir = "none";
  ASSERT_TRUE(uavsim::launch::resolve_run_files("test", &o, false));
  EXPECT_EQ(o.run_dir, "");
  EXPECT_EQ(o.record, "");
  EXPECT_EQ(o.json_path, "");
}

}  // namespace
