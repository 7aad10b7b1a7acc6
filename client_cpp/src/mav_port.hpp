// MavPort: what a protocol unit of the Vehicle (command sender, telemetry decoder, mission
// uploader, parameter client, GUIDED setpoints) needs from the link to its vehicle, and nothing
// more: send a message, hear the messages of one id, know whether the link is open and whom to
// address. The real port is MavlinkLink (a socket, with heartbeats and the lockstep hold); unit
// tests give the units a fake one, so each protocol is tested without sockets or a server. This is
// MAVSDK's plugin shape: each capability registers handlers for the message ids it owns.
//
// Library internal (not installed); loop thread only.
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <span>
#include <string>
#include <unordered_map>
#include <utility>

#include "uavsim/client/result.hpp"
#include "uavsim/common/mavlink/frame.hpp"
#include "uavsim/common/mavlink/generated/message_table.hpp"

namespace uavsim::client {

class MavPort {
 public:
  using Handler = std::function<void(const common::mavlink::Frame&)>;

  virtual ~MavPort() = default;

  // Whether the link is open: connected, and neither closed nor lost since.
  virtual bool is_open() const = 0;
  // The vehicle's ids, for the target fields of what is sent (0 before its first heartbeat).
  virtual std::uint8_t target_sysid() const = 0;
  virtual std::uint8_t target_compid() const = 0;
  // Where the link goes ("tcp:..."), for messages; empty before the first connect.
  virtual const std::string& address() const = 0;

  // Sends one generated message (msg::X) to the vehicle; false when it cannot go out (the link is
  // closed or was lost while sending).
  template <class Msg>
  bool send(const Msg& m) {
    std::array<std::uint8_t, Msg::kMaxLen> payload{};
    m.encode(payload.data());
    return send_payload({Msg::kId, Msg::kCrcExtra, Msg::kMinLen, Msg::kMaxLen, Msg::kName},
                        payload);
  }

  // Routes the vehicle's messages of one id to handler. One handler an id: every message belongs
  // to one unit, so no unit sees another's.
  void on_message(std::uint32_t msgid, Handler handler) { handlers_[msgid] = std::move(handler); }

  // kNotConnected naming the address, unless the link is open.
  Result<void> need_open() const {
    if (is_open()) return {};
    return Result<void>::fail(
        Error::kNotConnected,
        "not connected to a vehicle" + (address().empty() ? "" : " (" + address() + ")"));
  }

 protected:
  // Frames and sends a message's full payload (info.max_len bytes).
  virtual bool send_payload(const common::mavlink::MessageInfo& info,
                            std::span<const std::uint8_t> full_payload) = 0;

  // Hands one frame from the vehicle to the handler of its id; one nobody handles is dropped.
  void dispatch(const common::mavlink::Frame& f) const {
    if (auto it = handlers_.find(f.msgid); it != handlers_.end()) it->second(f);
  }

 private:
  std::unordered_map<std::uint32_t, Handler> handlers_;
};

}  // namespace uavsim::client
