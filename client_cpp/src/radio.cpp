#include "uavsim/client/radio.hpp"

#include <optional>
#include <string>

#include "lockstep_subscription.hpp"
#include "loop_services.hpp"
#include "sim_channel.hpp"
#include "uavsim/common/base64.hpp"
#include "uavsim/common/shm_requests.hpp"

namespace uavsim::client {

namespace {

using Json = nlohmann::json;

}  // namespace

struct A2aRadio::Impl {
  EventLoop& loop;
  int vehicle;
  std::uint64_t sink_id = 0;
  std::uint64_t radio_sink_id = 0;  // the tick records' frames (shared-memory stream)
  std::size_t max_frame_bytes = kRadioMaxFrameBytes;  // the channel's, from the subscription
  std::vector<RadioFrame> inbox;
  RadioCounters counters;
  std::uint32_t refusal_tag = 0;     // the channel's standing handler of this radio's refusals
  std::vector<std::uint8_t> record;  // a binary radio_send's payload (reused)

  Impl(EventLoop& l, int v) : loop(l), vehicle(v) {}

  // A radio_batch event: every frame the connection's vehicles received by this gate, each
  // [to, from, seq, broadcast, time, sent_time, data_b64] (docs/protocol.md, "Radio"), in order of
  // arrival. The connection may carry other vehicles' radios (several agents a process): only this
  // vehicle's frames are taken.
  void on_batch(const Json& e) {
    const auto it = e.find("frames");
    if (it == e.end() || !it->is_array()) return;
    for (const Json& f : *it) {
      if (!f.is_array() || f.size() != 7 || !f[0].is_number_integer() ||
          f[0].get<std::int64_t>() != vehicle) {
        continue;
      }
      take(f[1], f[3], f[4], f[6]);
    }
  }

  // A frame's fields, checked: a malformed one is dropped, whatever the server sent.
  void take(const Json& from, const Json& broadcast, const Json& time, const Json& data) {
    if (!data.is_string()) return;
    auto bytes = common::base64_decode(data.get_ref<const std::string&>());
    if (!bytes) return;
    take_frame(from.is_number_integer() ? from.get<int>() : -1,
               broadcast.is_boolean() ? broadcast.get<bool>() : true,
               time.is_number() ? time.get<double>() : 0.0, std::move(*bytes));
  }

  // A tick record's frame (its fields checked by the record's decoder), this vehicle's only.
  void on_frame(const common::shm::RadioFrame& f) {
    if (f.to != static_cast<std::uint32_t>(vehicle)) return;
    take_frame(static_cast<int>(f.from), f.broadcast, f.time_s, f.data);
  }

  void take_frame(int from, bool broadcast, double time_s, std::vector<std::uint8_t> bytes) {
    if (bytes.empty() || bytes.size() > kRadioLargestFrameBytes) return;
    RadioFrame f;
    f.time_s = time_s;
    f.from = from;
    f.broadcast = broadcast;
    f.data = std::move(bytes);
    inbox.push_back(std::move(f));
    ++counters.received;
  }
};

A2aRadio::A2aRadio(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}

A2aRadio::~A2aRadio() {
  if (SimChannel* channel = LoopServices(impl_->loop).sim_channel()) {
    channel->remove_event_sink(impl_->radio_sink_id);
    channel->remove_standing_reply(impl_->refusal_tag);
  }
  unsubscribe_lockstep_events(impl_->loop, impl_->sink_id,
                              {{"op", "radio_unsubscribe"}, {"vehicle", impl_->vehicle}});
}

int A2aRadio::vehicle() const { return impl_->vehicle; }

std::size_t A2aRadio::max_frame_bytes() const { return impl_->max_frame_bytes; }

const RadioCounters& A2aRadio::counters() const { return impl_->counters; }

std::vector<RadioFrame> A2aRadio::take_received() {
  impl_->loop.assert_in_loop_thread();
  std::vector<RadioFrame> out;
  out.swap(impl_->inbox);
  return out;
}

Result<void> A2aRadio::send(const std::vector<std::uint8_t>& data, int to) {
  impl_->loop.assert_in_loop_thread();
  if (data.empty() || data.size() > impl_->max_frame_bytes) {
    return Result<void>::fail(Error::kInvalidArgument,
                              "radio: a frame carries 1-" + std::to_string(impl_->max_frame_bytes) +
                                  " bytes, not " + std::to_string(data.size()));
  }
  Impl* s = impl_.get();
  SimChannel* channel = LoopServices(impl_->loop).sim_channel();
  if (channel == nullptr || !channel->is_open()) {
    return Result<void>::fail(Error::kConnectionLost, "radio: no simulator connection");
  }
  if (channel->has_request_ring() && !channel->outputs_held()) {
    // the binary form: no JSON, no base64, and a reply only if the server refuses it
    s->record.clear();
    common::shm::encode_radio_send(s->refusal_tag, static_cast<std::uint32_t>(s->vehicle),
                                   to >= 0 ? to : -1, data, &s->record);
    if (!channel->send_binary(common::shm::RecordType::kRadioSend, s->record)) {
      return Result<void>::fail(Error::kConnectionLost, "radio: no simulator connection");
    }
  } else {
    Json req = {
        {"op", "radio_send"}, {"vehicle", s->vehicle}, {"data_b64", common::base64_encode(data)}};
    if (to >= 0) {
      req["to"] = to;
    } else {
      req["to"] = "broadcast";
    }
    if (!channel->request(std::move(req), [s](const Json& j) {
          if (j.value("ok", false) != true) ++s->counters.refused;
        })) {
      return Result<void>::fail(Error::kConnectionLost, "radio: no simulator connection");
    }
  }
  ++impl_->counters.sent;
  return {};
}

Result<std::unique_ptr<A2aRadio>> A2aRadio::open(EventLoop& loop, int vehicle, double timeout_s) {
  using R = Result<std::unique_ptr<A2aRadio>>;
  loop.assert_in_loop_thread();
  if (!loop.is_lockstep()) {
    return R::fail(Error::kUnsupported, "radio: the simulator serves it to a lockstep loop only");
  }
  if (vehicle < 0) return R::fail(Error::kInvalidArgument, "radio: vehicle index must be >= 0");
  auto impl = std::make_unique<Impl>(loop, vehicle);
  Impl* s = impl.get();
  // batched: one line a gate for the connection, not one a frame (a flock's broadcasts fan out to
  // every neighbour, and a line each was most of an agent's parsing)
  // on the shared-memory stream the frames come with the tick, raw; the sink is in place before the
  // subscription, as the event sink is
  SimChannel* channel = LoopServices(loop).sim_channel();
  if (channel == nullptr) return R::fail(Error::kConnectionLost, "radio: no simulator connection");
  s->radio_sink_id =
      channel->add_radio_sink([s](const common::shm::RadioFrame& f) { s->on_frame(f); });
  Json result;
  auto id = subscribe_lockstep_events(
      loop, "radio_batch", [s](const Json& e) { s->on_batch(e); },
      {{"op", "radio_subscribe"}, {"vehicle", vehicle}, {"batch", true}}, timeout_s, "radio",
      "radio of vehicle " + std::to_string(vehicle), &result);
  if (!id) {
    channel->remove_event_sink(s->radio_sink_id);
    return R(id.error());
  }
  // the channel's frame size (a server without the field: 802.15.4's whole 127 bytes)
  if (auto it = result.find("max_frame_bytes");
      it != result.end() && it->is_number_unsigned() && it->get<std::uint64_t>() >= 1 &&
      it->get<std::uint64_t>() <= kRadioLargestFrameBytes) {
    s->max_frame_bytes = it->get<std::size_t>();
  }
  s->sink_id = *id;
  // a binary radio_send is answered only when refused (docs/protocol.md, "Shared-memory stream")
  s->refusal_tag = channel->add_standing_reply([s](const Json&) { ++s->counters.refused; });
  return std::unique_ptr<A2aRadio>(new A2aRadio(std::move(impl)));
}

}  // namespace uavsim::client
