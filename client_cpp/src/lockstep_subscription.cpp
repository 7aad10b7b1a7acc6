#include "lockstep_subscription.hpp"

#include <memory>
#include <optional>
#include <utility>

namespace uavsim::client {

Result<std::uint64_t> subscribe_lockstep_events(EventLoop& loop, const std::string& event,
                                                EventLoop::Impl::EventSink sink,
                                                nlohmann::json request, double timeout_s,
                                                const std::string& who,
                                                const std::string& subject) {
  using R = Result<std::uint64_t>;
  auto& li = loop.impl();
  const std::uint64_t id = li.next_event_sink++;
  li.event_sinks.emplace(event, std::make_pair(id, std::move(sink)));
  const std::string op = request.value("op", std::string());
  // the reply lives here until the wait below is over (the handler runs inside run_until)
  auto reply = std::make_shared<std::optional<nlohmann::json>>();
  if (!li.api_request(std::move(request), [reply](const nlohmann::json& j) { *reply = j; })) {
    remove_event_sink(loop, id);
    return R::fail(Error::kConnectionLost, who + ": no simulator connection");
  }
  if (auto w = loop.run_until([reply] { return reply->has_value(); }, timeout_s, op + "'s reply");
      !w) {
    remove_event_sink(loop, id);
    return R(w.error());
  }
  if ((*reply)->value("ok", false) != true) {
    remove_event_sink(loop, id);
    const nlohmann::json e = (*reply)->value("error", nlohmann::json::object());
    return R::fail(Error::kDenied, subject + ": " + e.value("code", std::string("?")) + ": " +
                                       e.value("message", std::string("?")));
  }
  return id;
}

void remove_event_sink(EventLoop& loop, std::uint64_t id) {
  auto& sinks = loop.impl().event_sinks;
  for (auto it = sinks.begin(); it != sinks.end(); ++it) {
    if (it->second.first == id) {
      sinks.erase(it);
      return;
    }
  }
}

}  // namespace uavsim::client
