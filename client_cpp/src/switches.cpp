#include "uavsim/client/switches.hpp"

#include <optional>

#include "event_loop_impl.hpp"

namespace uavsim::client {

namespace {
using Json = nlohmann::json;
}  // namespace

struct PadSwitches::Impl {
  EventLoop& loop;
  std::string vehicle;
  std::function<void(const SwitchState&)> on_change;
  std::uint64_t sink_id = 0;
  std::optional<Json> reply;
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

  void remove_sink() {
    auto& sinks = loop.impl().event_sinks;
    for (auto it = sinks.begin(); it != sinks.end(); ++it) {
      if (it->second.first == sink_id) {
        sinks.erase(it);
        return;
      }
    }
  }
};

PadSwitches::PadSwitches(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}

PadSwitches::~PadSwitches() {
  impl_->remove_sink();
  (void)impl_->loop.impl().api_request({{"op", "sensor_unsubscribe"}, {"vehicle", impl_->vehicle}},
                                       [](const Json&) {});
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
  auto& li = loop.impl();
  // the sink before the request: the first reading follows the reply at the next gate
  s->sink_id = li.next_event_sink++;
  li.event_sinks.emplace("sensor",
                         std::make_pair(s->sink_id, [s](const Json& e) { s->on_event(e); }));
  if (!li.api_request({{"op", "sensor_subscribe"}, {"vehicle", vehicle}},
                      [s](const Json& j) { s->reply = j; })) {
    s->remove_sink();
    return R::fail(Error::kConnectionLost, "pad switches: no simulator connection");
  }
  if (auto w = loop.run_until([s] { return s->reply.has_value(); }, timeout_s,
                              "sensor_subscribe's reply");
      !w) {
    s->remove_sink();
    return R(w.error());
  }
  if (s->reply->value("ok", false) != true) {
    s->remove_sink();
    const Json e = s->reply->value("error", Json::object());
    return R::fail(Error::kDenied, "pad switches of " + vehicle + ": " +
                                       e.value("code", std::string("?")) + ": " +
                                       e.value("message", std::string("?")));
  }
  return std::unique_ptr<PadSwitches>(new PadSwitches(std::move(impl)));
}

}  // namespace uavsim::client
