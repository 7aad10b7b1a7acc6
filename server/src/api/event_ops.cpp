#include "api/event_ops.hpp"

#include <algorithm>
#include <functional>
#include <optional>

#include "api/request_fields.hpp"
#include "sim/checked_number.hpp"

namespace uavsim::server::api {

EventOps::EventOps(sim::Simulation& sim, Send send) : sim_(sim), send_(std::move(send)) {}

void EventOps::register_ops(OpTable& table) {
  const OpRegistrar<EventOps> add(table, this, "events");
  add("events", &EventOps::op_events);
  add("subscribe_events", &EventOps::op_subscribe);
  add("unsubscribe_events", &EventOps::op_unsubscribe);
}

void EventOps::on_reset() {
  forwarded_ = 0;
  const Json reset{{"event", "reset"}, {"seed", sim_.config().seed}};
  for (uint64_t conn : subscribers_) send_(conn, reset);
}

void EventOps::forward() {
  const sim::EventLog& log = sim_.events();
  if (forwarded_ > log.next_seq()) forwarded_ = 0;  // the log was cleared (reset)
  // the log holds first_seq() onwards (called every step, so none is missed)
  for (const sim::Event& event : log.recent()) {
    if (event.seq < forwarded_) continue;
    const Json e = event_json(event);
    for (uint64_t conn : subscribers_) send_(conn, e);
  }
  forwarded_ = log.next_seq();
}

EventOps::Json EventOps::event_json(const sim::Event& e) const {
  const bool named = e.vehicle >= 0 && static_cast<size_t>(e.vehicle) < sim_.vehicle_count();
  return Json{{"event", "sim_event"},
              {"seq", e.seq},
              {"time", e.time_s},
              {"type", sim::event_type_name(e.type)},
              {"vehicle", e.vehicle},
              {"vehicle_name",
               named ? Json(sim_.vehicle_name(static_cast<size_t>(e.vehicle))) : Json(nullptr)},
              {"detail", e.detail}};
}

void EventOps::op_events(uint64_t, const Json& request, OpReply* reply) {
  const auto from_number = number_field(request, "from_seq");
  const auto from =
      from_number ? sim::checked_integer<uint64_t>(*from_number) : std::optional<uint64_t>(0);
  if (!from) return reply->fail(ApiError::kBadField, "\"from_seq\" must be a non-negative integer");
  // the events already forwarded (later ones stream to subscribers), from from_seq or the oldest
  // still held: first_seq > from_seq tells the client that the ones between were dropped
  const uint64_t from_seq = *from;
  const sim::EventLog& log = sim_.events();
  Json list = Json::array();
  for (const sim::Event& e : log.recent()) {
    if (e.seq >= from_seq && e.seq < forwarded_) list.push_back(event_json(e));
  }
  const uint64_t first_seq = std::min<uint64_t>(log.first_seq(), forwarded_);
  reply->result = {{"events", list}, {"first_seq", first_seq}, {"next_seq", forwarded_}};
}

void EventOps::op_subscribe(uint64_t conn, const Json& request, OpReply* reply) {
  // a subscriber gets the backlog in the reply; later events stream as {"event": "sim_event", ...}
  op_events(conn, request, reply);
  if (!reply->failed()) subscribers_.insert(conn);
}

void EventOps::op_unsubscribe(uint64_t conn, const Json&, OpReply*) { subscribers_.erase(conn); }

}  // namespace uavsim::server::api
