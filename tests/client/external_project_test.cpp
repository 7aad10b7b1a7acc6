// The client as an installed package: cmake --install this build tree into a staging prefix, build
// client_cpp/examples/external_project against it with find_package(uavsim) and, separately,
// hop.cpp with pkg-config's flags alone; then fly the find_package build against a uavsim-server on
// ephemeral ports (launched as the missions' launchers do, on the lockstep clock).
#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>

#include "uavsim/launch/launcher.hpp"

namespace {

namespace fs = std::filesystem;

// Runs a shell command, its output into log; true when it exits 0.
bool run(const std::string& cmd, const fs::path& log) {
  const std::string full = "(" + cmd + ") >>'" + log.string() + "' 2>&1";
  return std::system(full.c_str()) == 0;
}

std::string read_file(const fs::path& p) {
  std::string out;
  if (FILE* f = std::fopen(p.c_str(), "r")) {
    char buf[4096];
    for (std::size_t n; (n = std::fread(buf, 1, sizeof(buf), f)) > 0;) out.append(buf, n);
    std::fclose(f);
  }
  return out;
}

TEST(ExternalProject, BuildsAgainstTheInstalledPackageAndFlies) {
  const fs::path work = fs::path(UAVSIM_TEST_BINARY_DIR) / "external_project";
  fs::remove_all(work);
  fs::create_directories(work);
  const fs::path staging = work / "staging", log = work / "log.txt";
  const std::string q = "'";

  ASSERT_TRUE(run(
      "cmake --install " + q + UAVSIM_BUILD_DIR + q + " --prefix " + q + staging.string() + q, log))
      << read_file(log);
  ASSERT_TRUE(fs::exists(staging / "lib/cmake/uavsim/uavsimConfig.cmake")) << read_file(log);
  ASSERT_TRUE(fs::exists(staging / "lib/cmake/uavsim/uavsimConfigVersion.cmake"));
  ASSERT_TRUE(fs::exists(staging / "lib/pkgconfig/uavsim-client.pc"));
  // no server header travels with the client
  ASSERT_FALSE(fs::exists(staging / "include/sim")) << "server headers were installed";

  // find_package(uavsim): configure and build the example (same compiler, ccache when this build
  // has it)
  const fs::path example_build = work / "build";
  ASSERT_TRUE(run("cmake -S " + q + UAVSIM_SOURCE_DIR + "/client_cpp/examples/external_project" +
                      q + " -B " + q + example_build.string() + q + " -DCMAKE_PREFIX_PATH=" + q +
                      staging.string() + q + " -DCMAKE_CXX_COMPILER=" + q + UAVSIM_CXX_COMPILER +
                      q + " " + UAVSIM_EXTRA_CMAKE_ARGS,
                  log))
      << read_file(log);
  ASSERT_TRUE(run("cmake --build " + q + example_build.string() + q, log)) << read_file(log);
  const fs::path hop = example_build / "hop";
  ASSERT_TRUE(fs::exists(hop));

  // pkg-config: the same program from its flags alone
  ASSERT_TRUE(run("PKG_CONFIG_PATH=" + q + (staging / "lib/pkgconfig").string() + q + " " +
                      UAVSIM_CXX_COMPILER + " -std=c++20 -o " + q + (work / "hop_pc").string() + q +
                      " " + q + UAVSIM_SOURCE_DIR +
                      "/client_cpp/examples/external_project/hop.cpp" + q +
                      " $(PKG_CONFIG_PATH=" + q + (staging / "lib/pkgconfig").string() + q +
                      " pkg-config --cflags --libs uavsim-client) " + UAVSIM_EXTRA_LINK_FLAGS,
                  log))
      << read_file(log);

  // fly it: server on ephemeral ports, the program on the lockstep clock
  uavsim::launch::Launcher launcher("external_project", true);
  uavsim::launch::ServerSpec spec;
  spec.path = UAVSIM_SERVER;
  spec.world = std::string(UAVSIM_MODELS_DIR) + "/worlds/empty.xml";
  auto started = launcher.start_server(spec);
  ASSERT_TRUE(started) << started.error().message;
  const int port = launcher.mavlink_port("uav0");
  ASSERT_GT(port, 0);
  bool landed = false;
  std::string lines;
  launcher.on_line([&](const std::string& child, const std::string& line) {
    lines += "[" + child + "] " + line + "\n";
    if (child == "hop" && line.find("landed") != std::string::npos) landed = true;
  });
  auto spawned = launcher.spawn(
      "hop", {hop.string()},
      {"UAVSIM_MAVLINK=tcp:127.0.0.1:" + std::to_string(port), launcher.lockstep_env(0.02)});
  ASSERT_TRUE(spawned) << spawned.error().message;
  ASSERT_TRUE(launcher.wait_lockstep_clients(1, 60)) << lines;
  while (!launcher.programs_done() && launcher.wall_s() < 300) launcher.pump(100);
  launcher.stop_all(5);
  EXPECT_TRUE(landed) << lines;
}

}  // namespace
