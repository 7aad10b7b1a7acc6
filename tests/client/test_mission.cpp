// A mission process for the fault-isolation test: ordinary client code (clock from
// UAVSIM_LOCKSTEP), enables the vehicle's GCS failsafe, takes off, heads east and then just keeps
// its link alive until it is killed. Usage: client_test_mission tcp:HOST:PORT
#include <cstdio>

#include "uavsim/client/event_loop.hpp"
#include "uavsim/client/vehicle.hpp"

using namespace uavsim::client;

int main(int argc, char** argv) {
  if (argc < 2) return 2;
  auto loop = EventLoop::create();
  if (!loop) {
    std::fprintf(stderr, "mission: %s\n", loop.message().c_str());
    return 1;
  }
  // EventLoop::create() returns once joined and holding the first tick: the test waits for this
  // line (an event it can block on) before it starts the clock
  std::printf("mission: joined\n");
  std::fflush(stdout);
  Vehicle uav(**loop);
  auto step = [&](const char* what, const Result<void>& r) {
    if (!r) {
      std::fprintf(stderr, "mission: %s: %s\n", what, r.message().c_str());
      std::exit(1);
    }
  };
  step("connect", uav.connect(argv[1], 10));
  step("ready", uav.wait_ready(60));
  step("FS_GCS_ENABLE",
       uav.set_param("FS_GCS_ENABLE", 1));  // RTL when this process stops sending heartbeats
  step("GUIDED", uav.set_mode(FlightMode::kGuided));
  step("arm", uav.arm());
  step("take-off", uav.takeoff(10));
  step("goto", uav.goto_local_enu({30.0, 0.0, 10.0}));
  std::printf("mission: airborne\n");
  std::fflush(stdout);
  (*loop)->run();  // heartbeats until killed
  return 0;
}
