#include "lockstep_subscription.hpp"

#include <utility>

#include "loop_services.hpp"

namespace uavsim::client {

Result<std::uint64_t> subscribe_lockstep_events(EventLoop& loop, const std::string& event,
                                                SimChannel::EventSink sink, nlohmann::json request,
                                                double timeout_s, const std::string& who,
                                                const std::string& subject,
                                                nlohmann::json* result) {
  using R = Result<std::uint64_t>;
  SimChannel* channel = LoopServices(loop).sim_channel();
  if (channel == nullptr) return R::fail(Error::kConnectionLost, who + ": no simulator connection");
  const std::uint64_t id = channel->add_event_sink(event, std::move(sink));
  auto reply = call_and_wait(loop, *channel, std::move(request), timeout_s, who);
  if (!reply) {
    channel->remove_event_sink(id);
    return R(reply.error());
  }
  if (reply->value("ok", false) != true) {
    channel->remove_event_sink(id);
    return R::fail(Error::kDenied, subject + ": " + reply_error_text(*reply));
  }
  if (result != nullptr) *result = reply->value("result", nlohmann::json::object());
  return id;
}

void unsubscribe_lockstep_events(EventLoop& loop, std::uint64_t id, nlohmann::json request) {
  SimChannel* channel = LoopServices(loop).sim_channel();
  if (channel == nullptr) return;
  channel->remove_event_sink(id);
  (void)channel->request(std::move(request), [](const nlohmann::json&) {});
}

}  // namespace uavsim::client
