// The smallest flight: connect, arm, take off to 5 m, land. UAVSIM_MAVLINK=tcp:HOST:PORT picks the
// vehicle; UAVSIM_LOCKSTEP=HOST:PORT/PERIOD (simulator only) runs it on sim time.
#include <cstdio>

#include "uavsim/client/event_loop.hpp"
#include "uavsim/client/vehicle.hpp"

using namespace uavsim::client;

static int fail(const char* what, const Failure& f) {
  std::fprintf(stderr, "%s: %s (%s)\n", what, f.message.c_str(), error_name(f.code));
  return 1;
}

int main() {
  auto loop = EventLoop::create();
  if (!loop) return fail("event loop", loop.error());
  Vehicle uav(**loop);
  if (auto r = uav.connect(Vehicle::address_from_env(), 10); !r) return fail("connect", r.error());
  if (auto r = uav.wait_ready(60); !r) return fail("wait ready", r.error());
  if (auto r = uav.set_mode(FlightMode::kGuided); !r) return fail("GUIDED", r.error());
  if (auto r = uav.arm(); !r) return fail("arm", r.error());
  if (auto r = uav.takeoff(5); !r) return fail("take-off", r.error());
  std::printf("t=%.1f s at %.1f m\n", (*loop)->now(), uav.telemetry().position_enu_m.z());
  if (auto r = uav.land(true); !r) return fail("land", r.error());
  std::printf("t=%.1f s landed\n", (*loop)->now());
  return 0;
}
