// LoopConfig: the host clock by default, the lockstep clock from UAVSIM_LOCKSTEP (event_loop.hpp).
#include <cstdlib>
#include <string>

#include "uavsim/client/event_loop.hpp"
#include "uavsim/common/parse_number.hpp"

namespace uavsim::client {

LoopConfig LoopConfig::host() { return LoopConfig{}; }

LoopConfig LoopConfig::lockstep(const std::string& host, int port, double period_s) {
  LoopConfig c;
  c.clock = Clock::kLockstep;
  c.lockstep_host = host;
  c.lockstep_port = port;
  c.lockstep_period_s = period_s;
  return c;
}

LoopConfig LoopConfig::from_env() {
  LoopConfig c;
  const char* env = std::getenv("UAVSIM_LOCKSTEP");
  if (env == nullptr || *env == '\0') return c;
  const char* transport = std::getenv("UAVSIM_API_TRANSPORT");
  const std::string transport_name = transport != nullptr ? transport : "";
  const auto chosen = transport_name == "tcp"   ? LoopConfig::Transport::kTcp
                      : transport_name == "shm" ? LoopConfig::Transport::kShm
                                                : LoopConfig::Transport::kAuto;
  std::string spec = env;
  double period = c.lockstep_period_s;
  // a period or port that is not a whole number in range leaves the port invalid: create() reports
  // it
  bool ok = true;
  if (const auto slash = spec.find('/'); slash != std::string::npos) {
    ok = common::parse_double(spec.c_str() + slash + 1, 1e-4, 10.0, &period);
    spec.resize(slash);
  }
  const auto colon = spec.rfind(':');
  int port = -1;
  if (colon == std::string::npos || !ok ||
      !common::parse_integer(spec.c_str() + colon + 1, 1, 65535, &port)) {
    c.clock = Clock::kLockstep;
    c.lockstep_port = -1;  // reported by create()
    return c;
  }
  c = lockstep(spec.substr(0, colon), port, period);
  c.lockstep_transport = chosen;
  return c;
}

}  // namespace uavsim::client
