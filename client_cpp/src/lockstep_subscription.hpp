// Subscriptions to events streamed on the lockstep loop's simulator connection (the pad switches'
// "sensor" events, the radio's "radio_batch"): one way to set one up and take it down, so that the
// order that makes them deterministic lives in one place.
#pragma once

#include <cstdint>
#include <string>

#include <nlohmann/json.hpp>

#include "sim_channel.hpp"
#include "uavsim/client/event_loop.hpp"
#include "uavsim/client/result.hpp"

namespace uavsim::client {

// Registers `sink` for the events named `event` on the loop's simulator connection, then sends
// `request` (e.g. radio_subscribe) and waits for its reply. The sink is in place before the request
// goes out: the first events may follow the reply at the next gate. Returns the sink's id, or a
// failure (kConnectionLost "<who>: no simulator connection", the wait's failure, or kDenied
// "<subject>: code: message") with the sink removed. The reply's result goes to *result when given.
// Loop thread only.
Result<std::uint64_t> subscribe_lockstep_events(EventLoop& loop, const std::string& event,
                                                SimChannel::EventSink sink, nlohmann::json request,
                                                double timeout_s, const std::string& who,
                                                const std::string& subject,
                                                nlohmann::json* result = nullptr);

// Removes the sink registered under id and sends `request` (e.g. radio_unsubscribe) without waiting
// for its reply. Loop thread only.
void unsubscribe_lockstep_events(EventLoop& loop, std::uint64_t id, nlohmann::json request);

}  // namespace uavsim::client
