// Seed 6.1 fault isolation: a mission process dies mid-flight (SIGKILL); the vehicle's GCS failsafe
// (FS_GCS_ENABLE, armed by the mission) takes it home (RTL); a new process connects and takes over.
#include <gtest/gtest.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>

#include <cmath>

#include "sim_harness.hpp"
#include "uavsim/client/event_loop.hpp"
#include "uavsim/client/vehicle.hpp"

extern char** environ;

namespace uavsim::client::testing {
namespace {

TEST(FaultIsolation, KilledMissionProcessLeavesTheVehicleToTheFailsafeAndANewOneTakesOver) {
  SimServer server;
  auto l = EventLoop::create(LoopConfig::lockstep("127.0.0.1", server.api_port(), 0.02));
  ASSERT_TRUE(l) << l.message();
  EventLoop& loop = **l;
  ApiClient api(server.api_port());

  // the mission process, on the same lockstep clock
  const std::string lockstep = "UAVSIM_LOCKSTEP=127.0.0.1:" + std::to_string(server.api_port()) + "/0.02";
  std::vector<std::string> env_strings{lockstep};
  for (char** e = environ; *e != nullptr; ++e) {
    if (std::string(*e).rfind("UAVSIM_LOCKSTEP=", 0) != 0) env_strings.emplace_back(*e);
  }
  std::vector<char*> envp;
  for (auto& s : env_strings) envp.push_back(s.data());
  envp.push_back(nullptr);
  std::string exe = CLIENT_TEST_MISSION, addr = server.mavlink_address();
  char* argv[] = {exe.data(), addr.data(), nullptr};
  pid_t child = -1;
  ASSERT_EQ(posix_spawn(&child, exe.c_str(), nullptr, nullptr, argv, envp.data()), 0);
  struct Reaper {
    pid_t pid;
    ~Reaper() {
      if (pid > 0) {
        kill(pid, SIGKILL);
        waitpid(pid, nullptr, 0);
      }
    }
  } reaper{child};

  // let it join before the clock starts (the server is paused: wait in wall time)
  bool joined = false;
  for (int i = 0; i < 400 && !joined; ++i) {
    joined = api.request({{"op", "status"}})["result"].value("lockstep_clients", 0) >= 2;
    if (!joined) usleep(25000);
  }
  ASSERT_TRUE(joined) << "the mission process never joined the lockstep";
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
  r = loop.run_until([&] { return truth.value("mode", std::string()) == "RTL"; }, 15.0, "the GCS failsafe's RTL");
  ASSERT_TRUE(r) << r.message() << " mode " << truth.value("mode", std::string());
  EXPECT_GT(loop.now() - killed_at, 4.0);
  EXPECT_TRUE(truth.value("armed", false));
  // the vehicle had carried on to the last target meanwhile; now it comes home
  const double x_at_rtl = truth["position_enu_m"][0].get<double>();
  EXPECT_GT(x_at_rtl, x_at_kill);
  r = loop.run_until([&] { return truth["position_enu_m"][0].get<double>() < x_at_rtl - 5.0; }, 30.0,
                     "the vehicle to head home");
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
  const Eigen::Vector3d p(t["position_enu_m"][0].get<double>(), t["position_enu_m"][1].get<double>(),
                          t["position_enu_m"][2].get<double>());
  EXPECT_LT((p - target).norm(), 1.0) << p.transpose();
  EXPECT_EQ(t.value("mode", std::string()), "GUIDED");
  r = uav.land(true, 60);
  ASSERT_TRUE(r) << r.message();
  loop.cancel(poll);
}

}  // namespace
}  // namespace uavsim::client::testing
