// PadSwitches: a vehicle's landing-pad microswitches (seed 7.1, fig. 7.2), read as a drone's
// onboard computer reads its GPIO inputs. In the simulator they are the server's onboard sensor
// "switches" (docs/protocol.md "Onboard sensors"): every change of state arrives before the
// lockstep tick at whose sim time it happened, so a program sees a touchdown at the tick it occurs.
//
// Needs the lockstep clock (the subscription rides on the loop's simulator connection); on a real
// drone a GPIO driver would call the same on_change.
//
// Loop-thread only, like everything on an EventLoop.
#pragma once

#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "uavsim/client/event_loop.hpp"
#include "uavsim/client/result.hpp"

namespace uavsim::client {

struct SwitchState {
  double time_s = 0.0;       // sim time of the reading
  std::vector<bool> closed;  // one per pad, in the vehicle's order (pad0, pad1, ...)
  bool any() const {
    for (bool c : closed) {
      if (c) return true;
    }
    return false;
  }
};

class PadSwitches {
 public:
  // Subscribes to vehicle's switches (its simulator name, e.g. "uav0") and waits for the answer
  // (timeout_s on the loop clock). kUnsupported on the host clock; kDenied with the simulator's
  // message for an unknown vehicle or one without switches.
  static Result<std::unique_ptr<PadSwitches>> subscribe(
      EventLoop& loop, const std::string& vehicle,
      std::function<void(const SwitchState&)> on_change, double timeout_s = 10.0);
  ~PadSwitches();  // unsubscribes
  PadSwitches(const PadSwitches&) = delete;
  PadSwitches& operator=(const PadSwitches&) = delete;

  // The last state received (empty closed until the first reading).
  const SwitchState& state() const;

 private:
  struct Impl;
  explicit PadSwitches(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace uavsim::client
