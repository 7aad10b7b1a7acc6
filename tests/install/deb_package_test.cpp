// The Debian package (cpack -G DEB, the ctest fixture deb_package): its file list holds the
// programs, models, docs and client package under /usr; its Depends were computed from the binaries
// (the libraries they link), not listed by hand. Where the test runs as root with a working apt and
// no uavsim installed, it installs the package with apt, runs the installed server and a mission
// from /usr/bin, and removes it again with no file left behind.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "shell_run.hpp"

namespace {

namespace fs = std::filesystem;

using uavsim::tests::run_shell;
using uavsim::tests::ShellRun;

bool has(const std::string& text, const std::string& s) {
  return text.find(s) != std::string::npos;
}

// the one PACKAGE_*.deb the fixture made (empty when none)
fs::path deb_file(const std::string& package = "uavsim") {
  fs::path found;
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(UAVSIM_DEB_DIR, ec)) {
    const std::string name = e.path().filename().string();
    if (name.rfind(package + "_", 0) == 0 && e.path().extension() == ".deb") found = e.path();
  }
  return found;
}

// the files (not folders) the package installs, as absolute paths
std::vector<std::string> package_files(const fs::path& deb) {
  const ShellRun list = run_shell("dpkg-deb --fsys-tarfile '" + deb.string() + "' | tar -t");
  std::vector<std::string> files;
  std::istringstream in(list.output);
  for (std::string line; std::getline(in, line);) {
    if (line.empty() || line.back() == '/') continue;
    files.push_back(line.substr(line.rfind("./", 0) == 0 ? 1 : 0));
  }
  return files;
}

TEST(DebPackage, HoldsTheInstallUnderUsrWithDependsComputedFromTheBinaries) {
  const fs::path deb = deb_file();
  ASSERT_FALSE(deb.empty()) << "no uavsim_*.deb in " << UAVSIM_DEB_DIR
                            << " (the fixture deb_package makes it)";
  EXPECT_EQ(deb.filename().string().rfind(std::string("uavsim_") + UAVSIM_VERSION + "_", 0), 0u)
      << deb;
  std::printf("%s: %ju bytes\n", deb.filename().c_str(),
              static_cast<std::uintmax_t>(fs::file_size(deb)));

  const std::vector<std::string> files = package_files(deb);
  auto holds = [&](const std::string& f) {
    return std::find(files.begin(), files.end(), f) != files.end();
  };
  for (const char* f :
       {"/usr/bin/uavsim", "/usr/bin/uavsim-server", "/usr/bin/mbzirc2017-run",
        "/usr/bin/mbzirc2020-run", "/usr/bin/coverage-run", "/usr/bin/uavsim-plot",
        "/usr/share/uavsim/models/worlds/mbzirc2020.xml",
        "/usr/share/uavsim/models/common/ground.xml", "/usr/share/doc/uavsim/README.md",
        "/usr/share/bash-completion/completions/uavsim",
        "/usr/lib/cmake/uavsim/uavsimConfig.cmake"}) {
    EXPECT_TRUE(holds(f)) << f;
  }
  // nothing outside /usr (no build or source paths leaked into the package)
  for (const std::string& f : files) EXPECT_EQ(f.rfind("/usr/", 0), 0u) << f;
  // no GPL code: the ns3 radio helper is a package of its own (below)
  EXPECT_FALSE(holds("/usr/bin/uavsim-ns3-radio"));

  // Depends: dpkg-shlibdeps's packages of the linked libraries, with versions
  const std::string depends = run_shell("dpkg-deb -f '" + deb.string() + "' Depends").output;
  for (const char* lib :
       {"libc6 (>=", "libstdc++6 (>=", "libmujoco", "libosmesa6", "libopencv-core"}) {
    EXPECT_TRUE(has(depends, lib)) << lib << " not in Depends: " << depends;
  }
  EXPECT_FALSE(has(depends, "libns3")) << depends;
  const std::string recommends = run_shell("dpkg-deb -f '" + deb.string() + "' Recommends").output;
  EXPECT_TRUE(has(recommends, "ffmpeg")) << recommends;
}

// ns-3 is GPL-2.0-only: its helper program ships as uavsim-ns3-radio, with the GPL as its copyright
// file and the program's own source beside it, and depends on this very version of uavsim
TEST(DebPackage, TheNs3HelperIsAPackageOfItsOwnWithItsLicenceAndSource) {
#if !UAVSIM_HAS_NS3_HELPER
  GTEST_SKIP() << "this build has no ns3 radio helper (ns-3 is not installed)";
#endif
  const fs::path deb = deb_file("uavsim-ns3-radio");
  ASSERT_FALSE(deb.empty()) << "no uavsim-ns3-radio_*.deb in " << UAVSIM_DEB_DIR;
  EXPECT_EQ(
      deb.filename().string().rfind(std::string("uavsim-ns3-radio_") + UAVSIM_VERSION + "_", 0), 0u)
      << deb;
  const std::vector<std::string> files = package_files(deb);
  auto holds = [&](const std::string& f) {
    return std::find(files.begin(), files.end(), f) != files.end();
  };
  const std::string doc = "/usr/share/doc/uavsim-ns3-radio/";
  for (const std::string f : {std::string("/usr/bin/uavsim-ns3-radio"), doc + "copyright",
                              doc + "source/uavsim_ns3_radio.cc", doc + "source/wire.hpp",
                              doc + "source/CMakeLists.txt", doc + "source/README.md"}) {
    EXPECT_TRUE(holds(f)) << f;
  }
  for (const std::string& f : files) EXPECT_EQ(f.rfind("/usr/", 0), 0u) << f;
  const std::string copyright =
      run_shell("dpkg-deb --fsys-tarfile '" + deb.string() + "' | tar -xO ." + doc + "copyright")
          .output;
  EXPECT_TRUE(has(copyright, "SPDX-License-Identifier: GPL-2.0-only")) << copyright;
  const std::string depends = run_shell("dpkg-deb -f '" + deb.string() + "' Depends").output;
  EXPECT_TRUE(has(depends, std::string("uavsim (= ") + UAVSIM_VERSION + ")")) << depends;
  EXPECT_TRUE(has(depends, "libns3")) << depends;
}

TEST(DebPackage, InstallsWithAptRunsAndRemovesCleanly) {
  const fs::path deb = deb_file();
  ASSERT_FALSE(deb.empty());
  if (geteuid() != 0) GTEST_SKIP() << "not root: the package is not installed";
  if (run_shell("dpkg-query -W -f='${Status}' uavsim | grep -q 'install ok installed'").exit_code ==
      0) {
    GTEST_SKIP() << "a uavsim package is installed already: left alone";
  }
  // apt must be able to satisfy the package from what is installed or its sources
  const ShellRun dry = run_shell("apt-get install -s '" + deb.string() + "'");
  if (dry.exit_code != 0) GTEST_SKIP() << "apt cannot install it here: " << dry.output;

  // with the ns3 radio helper's package when this build made one: installed beside uavsim, it gives
  // the server its ns3 backend, and removing uavsim removes it too (it depends on uavsim)
  const fs::path ns3_deb = deb_file("uavsim-ns3-radio");
  // install, run, remove: one script under a lock (two checkouts on one machine must not overlap)
  const fs::path work = fs::path(::testing::TempDir()) / "deb";
  fs::remove_all(work);
  fs::create_directories(work);
  const std::string script = R"sh(set -e
export DEBIAN_FRONTEND=noninteractive
apt="apt-get -o DPkg::Lock::Timeout=300 -y -qq"
echo "start: $(date +%s.%N)"
$apt install ')sh" + deb.string() +
                             "' " + (ns3_deb.empty() ? "" : "'" + ns3_deb.string() + "'") +
                             R"sh( >/dev/null
echo "installed: $(date +%s.%N)"
trap '$apt remove --purge uavsim >/dev/null' EXIT
cd ')sh" + work.string() + R"sh('
echo "which: $(command -v uavsim-server)"
env -i PATH=/usr/bin:/bin HOME="$PWD" uavsim worlds
env -i PATH=/usr/bin:/bin HOME="$PWD" uavsim-server mbzirc2020 --fast --duration 0.2 --mavlink-port -1 --api-port -1 --quiet
echo "server: ok"
if command -v uavsim-ns3-radio >/dev/null; then
  env -i PATH=/usr/bin:/bin HOME="$PWD" uavsim-server empty --radio-backend ns3 --fast --duration 0.2 --mavlink-port -1 --api-port 0 --no-cameras --out none
fi
env -i PATH=/usr/bin:/bin HOME="$PWD" uavsim run mbzirc2017 --seed 1 --no-record --no-run-dir --budget 240 --wall-limit 600
echo "result: $(date +%s.%N)"
)sh";
  std::ofstream(work / "apt.sh") << script;
  const ShellRun r =
      run_shell("flock /tmp/uavsim-deb-test.lock bash '" + (work / "apt.sh").string() + "'");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  // the times (apt-get install to the mission's RESULT) for docs/results/install.md
  for (const char* stamp : {"start: ", "installed: ", "result: "}) {
    const std::size_t at = r.output.find(stamp);
    if (at != std::string::npos)
      std::printf("%s\n", r.output.substr(at, r.output.find('\n', at) - at).c_str());
  }
  EXPECT_TRUE(has(r.output, "which: /usr/bin/uavsim-server")) << r.output;
  EXPECT_TRUE(has(r.output, "# models: /usr/share/uavsim/models (install)")) << r.output;
  EXPECT_TRUE(has(r.output, "server: ok")) << r.output;
  EXPECT_TRUE(has(r.output, "RESULT: SUCCESS")) << r.output;
  if (!ns3_deb.empty()) {
    EXPECT_TRUE(has(r.output, "uavsim-server: radio: ns3 backend")) << r.output;
  }

  // removed: the package is gone and so is every file it brought
  EXPECT_NE(
      run_shell("dpkg-query -W -f='${Status}' uavsim | grep -q 'install ok installed'").exit_code,
      0);
  for (const std::string& f : package_files(deb))
    EXPECT_FALSE(fs::exists(f)) << f << " left behind";
  if (!ns3_deb.empty()) {
    for (const std::string& f : package_files(ns3_deb))
      EXPECT_FALSE(fs::exists(f)) << f << " left behind";
  }
  EXPECT_FALSE(fs::exists("/usr/share/uavsim")) << "/usr/share/uavsim left behind";
}

}  // namespace
