// Connect, wait until ready, arm, take off, fly a 20 m square, land. The same binary flies a real drone:
// UAVSIM_MAVLINK=tcp:HOST:PORT picks the vehicle; UAVSIM_LOCKSTEP=HOST:PORT (simulator only) runs on sim time.
#include <cstdio>

#include "uavsim/client/event_loop.hpp"
#include "uavsim/client/vehicle.hpp"

using namespace uavsim::client;

static int fail(const char* what, const Failure& f) {
  std::fprintf(stderr, "%s: %s (%s)\n", what, f.message.c_str(), error_name(f.code));
  return 1;
}

int main() {
  auto loop = EventLoop::create();  // host clock, or lockstep per UAVSIM_LOCKSTEP
  if (!loop) return fail("event loop", loop.error());
  Vehicle uav(**loop);
  if (auto r = uav.connect(Vehicle::address_from_env(), 10); !r) return fail("connect", r.error());
  if (auto r = uav.wait_ready(60); !r) return fail("wait ready", r.error());
  if (auto r = uav.set_mode(FlightMode::kGuided); !r) return fail("GUIDED", r.error());
  if (auto r = uav.arm(); !r) return fail("arm", r.error());
  if (auto r = uav.takeoff(10); !r) return fail("take-off", r.error());
  const Eigen::Vector3d home = uav.telemetry().position_enu_m;
  for (const auto& [east, north] : {std::pair{20.0, 0.0}, {20.0, 20.0}, {0.0, 20.0}, {0.0, 0.0}}) {
    const Eigen::Vector3d corner = home + Eigen::Vector3d(east, north, 0.0);
    if (auto r = uav.goto_local_enu(corner); !r) return fail("goto", r.error());
    if (auto r = uav.wait_position_enu(corner, 1.0, 60); !r) return fail("corner", r.error());
    std::printf("t=%.1f s corner (%.0f, %.0f) reached\n", (*loop)->now(), east, north);
  }
  if (auto r = uav.land(true); !r) return fail("land", r.error());
  std::printf("t=%.1f s landed\n", (*loop)->now());
  return 0;
}
