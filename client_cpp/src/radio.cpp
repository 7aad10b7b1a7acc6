#include "uavsim/client/radio.hpp"

#include <optional>
#include <string>

#include "event_loop_impl.hpp"
#include "lockstep_subscription.hpp"

namespace uavsim::client {

namespace {

using Json = nlohmann::json;

constexpr char kAlphabet[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";

std::string base64_encode(const std::vector<std::uint8_t>& bytes) {
  std::string out;
  out.reserve((bytes.size() + 2) / 3 * 4);
  for (std::size_t i = 0; i < bytes.size(); i += 3) {
    const std::uint32_t n = (std::uint32_t{bytes[i]} << 16) |
                            (i + 1 < bytes.size() ? std::uint32_t{bytes[i + 1]} << 8 : 0u) |
                            (i + 2 < bytes.size() ? std::uint32_t{bytes[i + 2]} : 0u);
    out.push_back(kAlphabet[(n >> 18) & 63]);
    out.push_back(kAlphabet[(n >> 12) & 63]);
    out.push_back(i + 1 < bytes.size() ? kAlphabet[(n >> 6) & 63] : '=');
    out.push_back(i + 2 < bytes.size() ? kAlphabet[n & 63] : '=');
  }
  return out;
}

int sextet(char c) {
  if (c >= 'A' && c <= 'Z') return c - 'A';
  if (c >= 'a' && c <= 'z') return c - 'a' + 26;
  if (c >= '0' && c <= '9') return c - '0' + 52;
  if (c == '+') return 62;
  if (c == '/') return 63;
  return -1;
}

// what the server sends is canonical base64; anything else is dropped
std::optional<std::vector<std::uint8_t>> base64_decode(const std::string& text) {
  std::size_t len = text.size();
  while (len > 0 && text[len - 1] == '=') --len;
  std::vector<std::uint8_t> out;
  out.reserve(len * 3 / 4);
  std::uint32_t acc = 0;
  int bits = 0;
  for (std::size_t i = 0; i < len; ++i) {
    const int v = sextet(text[i]);
    if (v < 0) return std::nullopt;
    acc = (acc << 6) | static_cast<std::uint32_t>(v);
    bits += 6;
    if (bits >= 8) {
      bits -= 8;
      out.push_back(static_cast<std::uint8_t>((acc >> bits) & 0xFF));
    }
  }
  return out;
}

}  // namespace

struct A2aRadio::Impl {
  EventLoop& loop;
  int vehicle;
  std::uint64_t sink_id = 0;
  std::vector<RadioFrame> inbox;
  RadioCounters counters;

  Impl(EventLoop& l, int v) : loop(l), vehicle(v) {}

  void on_event(const Json& e) {
    const Json to = e.value("to", Json());
    if (!to.is_number_integer() || to.get<int>() != vehicle) return;
    const Json data = e.value("data_b64", Json());
    if (!data.is_string()) return;
    auto bytes = base64_decode(data.get<std::string>());
    if (!bytes || bytes->empty() || bytes->size() > kRadioMaxFrameBytes) return;
    RadioFrame f;
    f.time_s = e.value("time", 0.0);
    const Json from = e.value("from", Json());
    f.from = from.is_number_integer() ? from.get<int>() : -1;
    f.broadcast = e.value("broadcast", true);
    f.data = std::move(*bytes);
    inbox.push_back(std::move(f));
    ++counters.received;
  }
};

A2aRadio::A2aRadio(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}

A2aRadio::~A2aRadio() {
  remove_event_sink(impl_->loop, impl_->sink_id);
  (void)impl_->loop.impl().api_request({{"op", "radio_unsubscribe"}, {"vehicle", impl_->vehicle}},
                                       [](const Json&) {});
}

int A2aRadio::vehicle() const { return impl_->vehicle; }

const RadioCounters& A2aRadio::counters() const { return impl_->counters; }

std::vector<RadioFrame> A2aRadio::take_received() {
  impl_->loop.assert_in_loop_thread();
  std::vector<RadioFrame> out;
  out.swap(impl_->inbox);
  return out;
}

Result<void> A2aRadio::send(const std::vector<std::uint8_t>& data, int to) {
  impl_->loop.assert_in_loop_thread();
  if (data.empty() || data.size() > kRadioMaxFrameBytes) {
    return Result<void>::fail(Error::kInvalidArgument, "radio: a frame carries 1-127 bytes, not " +
                                                           std::to_string(data.size()));
  }
  Json req = {{"op", "radio_send"}, {"vehicle", impl_->vehicle}, {"data_b64", base64_encode(data)}};
  if (to >= 0) {
    req["to"] = to;
  } else {
    req["to"] = "broadcast";
  }
  Impl* s = impl_.get();
  if (!impl_->loop.impl().api_request(std::move(req), [s](const Json& j) {
        if (j.value("ok", false) != true) ++s->counters.refused;
      })) {
    return Result<void>::fail(Error::kConnectionLost, "radio: no simulator connection");
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
  auto id = subscribe_lockstep_events(
      loop, "radio", [s](const Json& e) { s->on_event(e); },
      {{"op", "radio_subscribe"}, {"vehicle", vehicle}}, timeout_s, "radio",
      "radio of vehicle " + std::to_string(vehicle));
  if (!id) return R(id.error());
  s->sink_id = *id;
  return std::unique_ptr<A2aRadio>(new A2aRadio(std::move(impl)));
}

}  // namespace uavsim::client
