#include "uavsim/client/switches.hpp"

#include <optional>

#include "lockstep_subscription.hpp"

namespace uavsim::client {

namespace {
using Json = nlohmann::json;
}  // namespace

struct PadSwitches::Impl {
  EventLoop& loop;
  std::string vehicle;
  std::function<void(const SwitchState&)> on_change;
  std::uint64_t sink_id = 0;
  SwitchState state;

  Impl(EventLoop& l, std::string v) : loop(l), vehicle(std::move(v)) {}

  void on_event(const Json& e) {
    if (e.value("vehicle", std::string()) != vehicle ||
        e.value("sensor", std::string()) != "switches")
      return;
    const Json closed = e.value("closed", Json::array());
    if (!closed.is_array()) return;
    SwitchState s;
    s.time_s = e.value("time", 0.0);
    for (const Json& c : closed) s.closed.push_back(c.is_boolean() && c.get<bool>());
    state = s;
    if (on_change) on_change(state);
  }
};

PadSwitches::PadSwitches(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}

PadSwitches::~PadSwitches() {
  unsubscribe_lockstep_events(impl_->loop, impl_->sink_id,
                              {{"op", "sensor_unsubscribe"}, {"vehicle", impl_->vehicle}});
}

const SwitchState& PadSwitches::state() const { return impl_->state; }

Result<std::unique_ptr<PadSwitches>> PadSwitches::subscribe(
    EventLoop& loop, const std::string& vehicle, std::function<void(const SwitchState&)> on_change,
    double timeout_s) {
  using R = Result<std::unique_ptr<PadSwitches>>;
  loop.assert_in_loop_thread();
  if (!loop.is_lockstep()) {
    return R::fail(Error::kUnsupported,
                   "pad switches: the simulator serves them to a lockstep loop only");
  }
  auto impl = std::make_unique<Impl>(loop, vehicle);
  impl->on_change = std::move(on_change);
  Impl* s = impl.get();
  auto id = subscribe_lockstep_events(
      loop, "sensor", [s](const Json& e) { s->on_event(e); },
      {{"op", "sensor_subscribe"}, {"vehicle", vehicle}}, timeout_s, "pad switches",
      "pad switches of " + vehicle);
  if (!id) return R(id.error());
  s->sink_id = *id;
  return std::unique_ptr<PadSwitches>(new PadSwitches(std::move(impl)));
}

}  // namespace uavsim::client
