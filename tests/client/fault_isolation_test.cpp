// Seed 6.1 fault isolation: a mission process dies mid-flight (SIGKILL); the vehicle's GCS failsafe
// (FS_GCS_ENABLE, armed by the mission) takes it home (RTL); a new process connects and takes over.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <poll.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cmath>

#include "sim_harness.hpp"
#include "uavsim/client/event_loop.hpp"
#include "uavsim/client/vehicle.hpp"

extern char** environ;

namespace uavsim::client::testing {
namespace {

// A process start under a sanitizer on a loaded machine takes seconds, not minutes.
constexpr int kJoinWaitMs = 120000;

// Reads fd until a line `line` has arrived, EOF, or `timeout_ms` without it; returns what was read.
std::string read_until_line(int fd, const std::string& line, int timeout_ms) {
  std::string got;
  char buf[512];
  while (got.find(line + "\n") == std::string::npos) {
    pollfd p{fd, POLLIN, 0};
    if (poll(&p, 1, timeout_ms) <= 0) break;
    const ssize_t n = read(fd, buf, sizeof buf);
    if (n <= 0) break;
    got.append(buf, static_cast<size_t>(n));
  }
  return got;
}

TEST(FaultIsolation, KilledMissionProcessLeavesTheVehicleToTheFailsafeAndANewOneTakesOver) {
  SimServer server;
  auto l = EventLoop::create(LoopConfig::lockstep("127.0.0.1", server.api_port(), 0.02));
  ASSERT_TRUE(l) << l.message();
  EventLoop& loop = **l;
  ApiClient api(server.api_port());

  // the mission process, on the same lockstep clock
  const std::string lockstep =
      "UAVSIM_LOCKSTEP=127.0.0.1:" + std::to_string(server.api_port()) + "/0.02";
  std::vector<std::string> env_strings{lockstep};
  for (char** e = environ; *e != nullptr; ++e) {
    if (std::string(*e).rfind("UAVSIM_LOCKSTEP=", 0) != 0) env_strings.emplace_back(*e);
  }
  std::vector<char*> envp;
  for (auto& s : env_strings) envp.push_back(s.data());
  envp.push_back(nullptr);
  std::string exe = CLIENT_TEST_MISSION, addr = server.mavlink_address();
  char* argv[] = {exe.data(), addr.data(), nullptr};
  // its standard output comes back on a pipe: it says when it has joined the lockstep
  int out[2];
  ASSERT_EQ(pipe2(out, O_CLOEXEC), 0);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_adddup2(&actions, out[1], STDOUT_FILENO);
  pid_t child = -1;
  const int spawned = posix_spawn(&child, exe.c_str(), &actions, nullptr, argv, envp.data());
  posix_spawn_file_actions_destroy(&actions);
  close(out[1]);
  ASSERT_EQ(spawned, 0);
  struct Reaper {
    pid_t pid;
    int out_fd;  // held open until the child is gone: its later lines must not meet a closed pipe
                 // (SIGPIPE)
    ~Reaper() {
      if (pid > 0) {
        kill(pid, SIGKILL);
        waitpid(pid, nullptr, 0);
      }
      close(out_fd);
    }
  } reaper{child, out[0]};

  // let it join before the clock starts: the server is paused until its "joined" line (the bound is
  // only for a process that never gets there; it does not pace the test)
  const std::string said = read_until_line(out[0], "mission: joined", kJoinWaitMs);
  ASSERT_NE(said.find("mission: joined"), std::string::npos)
      << "the mission process never joined: " << said;
  ASSERT_GE(api.request({{"op", "status"}})["result"].value("lockstep_clients", 0), 2);
  ASSERT_EQ(api.request({{"op", "resume"}}).value("ok", false), true);

  Json truth;
  const TimerId poll = loop.call_every(0.5, [&] { truth = api.truth(); });
  auto r = loop.run_until(
      [&] {
        return truth.is_object() && truth["position_enu_m"][2].get<double>() > 9.0 &&
               truth["position_enu_m"][0].get<double>() > 8.0;
      },
      120.0, "the mission to fly east at 10 m");
  ASSERT_TRUE(r) << r.message();

  // crash the mission process mid-flight
  ASSERT_EQ(kill(child, SIGKILL), 0);
  int status = 0;
  ASSERT_EQ(waitpid(child, &status, 0), child);
  reaper.pid = -1;
  const double killed_at = loop.now();
  const double x_at_kill = truth["position_enu_m"][0].get<double>();

  // the server-side failsafe: RTL once no GCS heartbeat for FS_GCS_TIMEOUT (5 s)
  r = loop.run_until([&] { return truth.value("mode", std::string()) == "RTL"; }, 15.0,
                     "the GCS failsafe's RTL");
  ASSERT_TRUE(r) << r.message() << " mode " << truth.value("mode", std::string());
  EXPECT_GT(loop.now() - killed_at, 4.0);
  EXPECT_TRUE(truth.value("armed", false));
  // the vehicle had carried on to the last target meanwhile; now it comes home
  const double x_at_rtl = truth["position_enu_m"][0].get<double>();
  EXPECT_GT(x_at_rtl, x_at_kill);
  r = loop.run_until([&] { return truth["position_enu_m"][0].get<double>() < x_at_rtl - 5.0; },
                     30.0, "the vehicle to head home");
  ASSERT_TRUE(r) << r.message();

  // a restarted mission process (here: this one) connects and takes over
  Vehicle uav(loop);
  r = uav.connect(server.mavlink_address(), 10);
  ASSERT_TRUE(r) << r.message();
  r = uav.wait_ready(10);
  ASSERT_TRUE(r) << r.message();
  EXPECT_EQ(uav.telemetry().mode, FlightMode::kRtl);
  EXPECT_TRUE(uav.telemetry().armed);
  r = uav.set_mode(FlightMode::kGuided);
  ASSERT_TRUE(r) << r.message();
  const Eigen::Vector3d target(0.0, 15.0, 12.0);
  ASSERT_TRUE(uav.goto_local_enu(target));
  r = uav.wait_position_enu(target, 0.7, 60);
  ASSERT_TRUE(r) << r.message();
  ASSERT_TRUE(loop.run_for(1.0));
  const Json t = api.truth();
  const Eigen::Vector3d p(t["position_enu_m"][0].get<double>(),
                          t["position_enu_m"][1].get<double>(),
                          t["position_enu_m"][2].get<double>());
  EXPECT_LT((p - target).norm(), 1.0) << p.transpose();
  EXPECT_EQ(t.value("mode", std::string()), "GUIDED");
  r = uav.land(true, 60);
  ASSERT_TRUE(r) << r.message();
  loop.cancel(poll);
}

}  // namespace
}  // namespace uavsim::client::testing
