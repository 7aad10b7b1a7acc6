// uavsim as a user of an install meets it: `cmake --install` of this build into a prefix (the ctest
// fixture install_prefix), then the front door, the server on every shipped world, a world of one's
// own that includes shipped parts, and the MBZIRC 2017 launcher to its RESULT line, all run from
// the prefix with a clean environment, in an empty folder, and - where the kernel lets the test
// make a mount namespace - with the source and build trees hidden under empty mounts and the prefix
// seen at another path (so an install that still reached into the source tree, or only worked where
// it was installed, fails here).
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "shell_run.hpp"

namespace {

namespace fs = std::filesystem;

using uavsim::tests::run_shell;
using uavsim::tests::ShellRun;

bool has(const ShellRun& r, const std::string& s) { return r.output.find(s) != std::string::npos; }

std::string quoted(const std::string& s) {
  std::string q = "'";
  for (char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

// Whether this process may make a mount namespace (as root, or through a user namespace).
bool can_hide_trees() {
  static const bool can = run_shell("unshare -rm true").exit_code == 0;
  return can;
}

class InstalledTree : public ::testing::Test {
 protected:
  void SetUp() override {
    ASSERT_TRUE(fs::exists(fs::path(UAVSIM_INSTALL_PREFIX) / "bin/uavsim"))
        << "no install in " << UAVSIM_INSTALL_PREFIX
        << " (the fixture test install_prefix makes it)";
    work_ = fs::path(::testing::TempDir()) / "installed";
    fs::remove_all(work_);
    fs::create_directories(work_ / "home");
    fs::create_directories(work_ / "prefix");
  }

  // The prefix as the commands see it.
  std::string prefix() const {
    return can_hide_trees() ? (work_ / "prefix").string() : UAVSIM_INSTALL_PREFIX;
  }
  // The command's working folder (empty at the start of each test).
  fs::path home() const { return work_ / "home"; }

  // Runs a shell command line as a user of the install: PATH = PREFIX/bin and the system's, nothing
  // else of this environment, cwd home(); the source and build trees hidden when can_hide_trees().
  ShellRun run(const std::string& command_line) const {
    const fs::path script = work_ / "run.sh";
    std::ofstream s(script);
    s << "set -e\n";
    if (can_hide_trees()) {
      // the prefix at another path first (it lives in the build tree), then the trees under empty
      // mounts, the deeper first (build/ is often inside the source tree)
      std::vector<std::string> trees{UAVSIM_SOURCE_DIR, UAVSIM_BUILD_DIR};
      std::sort(trees.begin(), trees.end(),
                [](const std::string& a, const std::string& b) { return a.size() > b.size(); });
      s << "mount --bind " << quoted(UAVSIM_INSTALL_PREFIX) << " " << quoted(prefix()) << "\n";
      for (const std::string& t : trees) s << "mount -t tmpfs none " << quoted(t) << "\n";
    }
    s << "cd " << quoted(home().string()) << "\n"
      << "exec env -i PATH=" << quoted(prefix() + "/bin:/usr/bin:/bin")
      << " HOME=" << quoted(home().string()) << " TMPDIR=" << quoted(home().string())
      << " LANG=C.UTF-8 sh -c " << quoted(command_line) << "\n";
    s.close();
    return run_shell((can_hide_trees() ? "unshare -rm sh " : "sh ") + quoted(script.string()));
  }

  fs::path work_;
};

std::vector<std::string> source_worlds() {
  std::vector<std::string> names;
  for (const auto& e : fs::directory_iterator(fs::path(UAVSIM_MODELS_DIR) / "worlds")) {
    if (e.path().extension() == ".xml") names.push_back(e.path().stem().string());
  }
  std::sort(names.begin(), names.end());
  return names;
}

TEST_F(InstalledTree, HoldsTheProgramsModelsDocsAndTheClientPackage) {
  const fs::path p = UAVSIM_INSTALL_PREFIX;
  for (const char* f : {"bin/uavsim",
                        "bin/uavsim-server",
                        "bin/uavsim-plot",
                        "bin/uavsim-videolog-export",
                        "bin/mbzirc2017-run",
                        "bin/mbzirc2017-uav",
                        "bin/mbzirc2020-run",
                        "bin/mbzirc2020-uav",
                        "bin/mbzirc2020-gcs",
                        "bin/coverage-run",
                        "bin/coverage-agent",
                        "bin/coverage-gcs",
                        "share/uavsim/models/common/ground.xml",
                        "share/uavsim/models/vehicles/quad.xml",
                        "share/uavsim/models/objects/truck_marker.png",
                        "share/doc/uavsim/README.md",
                        "share/doc/uavsim/LICENSE",
                        "share/doc/uavsim/docs/protocol.md",
                        "share/bash-completion/completions/uavsim",
                        "lib/cmake/uavsim/uavsimConfig.cmake",
                        "lib/pkgconfig/uavsim-client.pc",
                        "include/uavsim/client/vehicle.hpp",
                        "include/uavsim/media/media_io.hpp",
                        "lib/libuavsim_media.a",
                        "lib/uavsim/libuavsim_media_io.so"}) {
    EXPECT_TRUE(fs::exists(p / f)) << f;
  }
  for (const std::string& w : source_worlds()) {
    EXPECT_TRUE(fs::exists(p / "share/uavsim/models/worlds" / (w + ".xml"))) << w;
  }
}

TEST_F(InstalledTree, FrontDoorSaysItsVersionAndListsTheMissionsAndWorlds) {
  std::printf("source and build trees %s\n",
              can_hide_trees() ? "hidden (mount namespace)" : "visible");
  ShellRun r = run("uavsim --version");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(r.output, std::string("uavsim ") + UAVSIM_VERSION + "\n");
  r = run("uavsim help");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  for (const char* m : {"mbzirc2017", "mbzirc2020", "coverage"})
    EXPECT_TRUE(has(r, "  " + std::string(m) + " ")) << r.output;
  for (const std::string& w : source_worlds())
    EXPECT_TRUE(has(r, "\n  " + w + " ")) << w << "\n" << r.output;
  // the worlds come from the prefix, found beside its bin/
  r = run("uavsim worlds");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(r.output.rfind("# models: " + prefix() + "/share/uavsim/models (install)\n", 0), 0u)
      << r.output;
  r = run("uavsim worlds --names");
  std::string names;
  for (const std::string& w : source_worlds()) names += w + "\n";
  EXPECT_EQ(r.output, names);
}

TEST_F(InstalledTree, FrontDoorRefusesWhatItCannotRunAndSaysWhy) {
  ShellRun r = run("uavsim run no_such_mission");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_TRUE(has(r, "no mission 'no_such_mission'")) << r.output;
  EXPECT_TRUE(has(r, "mbzirc2017")) << r.output;
  r = run("uavsim run ../bin/uavsim");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_TRUE(has(r, "is not a mission name")) << r.output;
  r = run("uavsim frobnicate");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_TRUE(has(r, "no command 'frobnicate'")) << r.output;
  r = run("uavsim server no_such_world --duration 1");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_TRUE(has(r, "the shipped worlds are")) << r.output;
  // sweep runs uavsim-sweep where it is installed, and says so where it is not
  r = run("uavsim sweep --help");
  if (fs::exists(fs::path(UAVSIM_INSTALL_PREFIX) / "bin/uavsim-sweep")) {
    EXPECT_EQ(r.exit_code, 0) << r.output;
  } else {
    EXPECT_EQ(r.exit_code, 2);
    EXPECT_TRUE(has(r, "uavsim-sweep is not installed")) << r.output;
  }
}

TEST_F(InstalledTree, BashCompletionOffersCommandsWorldsAndMissions) {
  const std::string completion = prefix() + "/share/bash-completion/completions/uavsim";
  auto complete = [&](const std::string& words, int cword) {
    return run("bash -c " + quoted(". " + completion + "; COMP_WORDS=(" + words + "); COMP_CWORD=" +
                                   std::to_string(cword) + "; _uavsim; echo \"${COMPREPLY[*]}\""));
  };
  EXPECT_TRUE(has(complete("uavsim se", 1), "server")) << complete("uavsim se", 1).output;
  const ShellRun worlds = complete("uavsim server mbz", 2);
  EXPECT_TRUE(has(worlds, "mbzirc2017")) << worlds.output;
  EXPECT_TRUE(has(worlds, "mbzirc2020")) << worlds.output;
  const ShellRun missions = complete("uavsim run c", 2);
  EXPECT_EQ(missions.output, "coverage\n");
}

TEST_F(InstalledTree, ServerRunsEveryShippedWorldByName) {
  for (const std::string& w : source_worlds()) {
    // a fifth of a sim second, as fast as it goes, no endpoints: the world loads and steps
    const ShellRun r = run("uavsim server " + w +
                           " --fast --duration 0.2 --mavlink-port -1 --api-port -1 --quiet");
    EXPECT_EQ(r.exit_code, 0) << w << "\n" << r.output;
  }
  // the server's own name works as well as the front door
  const ShellRun r =
      run("uavsim-server mbzirc2020 --fast --duration 0.2 --mavlink-port -1 --api-port -1 --quiet");
  EXPECT_EQ(r.exit_code, 0) << r.output;
}

TEST_F(InstalledTree, AWorldOfOnesOwnIncludesTheShippedParts) {
  // written in the working folder, far from the models: the include resolves in the install's
  // models
  std::ofstream(home() / "mine.xml") << R"(<mujoco model="mine">
  <compiler angle="radian"/>
  <option timestep="0.001" integrator="Euler"/>
  <include file="../common/ground.xml"/>
  <worldbody>
    <uavsim_vehicle type="hexa" name="h0" pos="0 0 0"/>
    <uavsim_object type="balloon" name="b0" pos="5 0 0"/>
  </worldbody>
</mujoco>)";
  const ShellRun r =
      run("uavsim server mine.xml --fast --duration 0.2 --mavlink-port -1 --api-port -1 --quiet");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  const ShellRun w =
      run("uavsim-server mine.xml --write-world composed.xml && grep -c 'name=\"ground\"' "
          "composed.xml");
  EXPECT_EQ(w.exit_code, 0) << w.output;
}

// OpenCV's image codecs and video files are a module the programs open on first use
// (PREFIX/lib/uavsim/libuavsim_media_io.so): the server's recording checks its finished video
// through it, and a module it could not find would stop the video with the reason
TEST_F(InstalledTree, TheServerOpensTheCodecsModuleOfTheInstall) {
  const ShellRun r = run(
      "uavsim-server mbzirc2017 --fast --duration 1 --mavlink-port -1 --api-port -1 --quiet "
      "--record rec.mp4 --record-size 160x120");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_TRUE(has(r, "recorded 15 frames to rec.mp4")) << r.output;
  EXPECT_FALSE(has(r, "cannot be loaded")) << r.output;
  EXPECT_FALSE(has(r, "the video stops here")) << r.output;
  EXPECT_GT(fs::file_size(home() / "rec.mp4"), 0u);
}

TEST_F(InstalledTree, Mbzirc2017LauncherLandsAndItsRunPlots) {
  const ShellRun r =
      run("uavsim run mbzirc2017 --seed 1 --no-record --budget 240 --wall-limit 600");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_TRUE(has(r, "RESULT: SUCCESS")) << r.output;
  // the run directory under the working folder, and its pictures where matplotlib is there
  std::string run_dir;
  for (const auto& e : fs::directory_iterator(home() / "runs"))
    run_dir = e.path().filename().string();
  ASSERT_EQ(run_dir.rfind("mbzirc2017-seed1-", 0), 0u) << run_dir;
  const ShellRun plot = run("uavsim plot runs/" + run_dir);
  if (plot.exit_code == 3) GTEST_SKIP() << "matplotlib is not installed: " << plot.output;
  EXPECT_EQ(plot.exit_code, 0) << plot.output;
  EXPECT_TRUE(fs::exists(home() / "runs" / run_dir / "trajectories.png")) << plot.output;
}

}  // namespace
