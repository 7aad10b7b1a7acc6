// A fake vehicle link for the Vehicle's capability units (client_cpp/src): it records every message
// a unit sends, lets a test script the vehicle's answers, and hands frames to the units exactly as
// MavlinkLink does (by message id). No sockets, no server: the units run on a host-clock EventLoop,
// and answers arrive through the loop (posted), never inside the send that caused them, as on a
// real link.
#pragma once

#include <gtest/gtest.h>

#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "mav_port.hpp"
#include "uavsim/client/event_loop.hpp"
#include "uavsim/common/mavlink/generated/messages.hpp"

namespace uavsim::client::testing {

class FakeMavPort : public MavPort {
 public:
  struct Sent {
    std::uint32_t msgid = 0;
    std::vector<std::uint8_t> payload;  // the full payload (kMaxLen bytes)
  };

  explicit FakeMavPort(EventLoop& loop) : loop_(loop) {}

  bool open = true;
  std::uint8_t sysid = 1;
  std::uint8_t compid = 1;
  std::string where = "fake:1";
  // the scripted vehicle: sees every message sent, answers with reply()
  std::function<void(const Sent&)> vehicle;

  bool is_open() const override { return open; }
  std::uint8_t target_sysid() const override { return sysid; }
  std::uint8_t target_compid() const override { return compid; }
  const std::string& address() const override { return where; }

  // Every message of type Msg sent so far, decoded.
  template <class Msg>
  std::vector<Msg> sent() const {
    std::vector<Msg> out;
    for (const Sent& s : log_) {
      if (s.msgid == Msg::kId) out.push_back(Msg::decode(s.payload.data()));
    }
    return out;
  }
  std::size_t sent_count() const { return log_.size(); }

  // A message from the vehicle, handled now (as the link does after reading it).
  template <class Msg>
  void deliver(const Msg& m) {
    common::mavlink::Frame f;
    f.msgid = Msg::kId;
    f.sysid = sysid;
    f.compid = compid;
    f.payload_len = Msg::kMaxLen;
    f.info = common::mavlink::find_message_info(Msg::kId);
    m.encode(f.payload.data());
    dispatch(f);
  }
  // The same, through the loop: the vehicle's answer to what was just sent.
  template <class Msg>
  void reply(const Msg& m) {
    loop_.post([this, m] { deliver(m); });
  }

 protected:
  bool send_payload(const common::mavlink::MessageInfo& info,
                    std::span<const std::uint8_t> full_payload) override {
    if (!open) return false;
    log_.push_back({info.id, {full_payload.begin(), full_payload.end()}});
    if (vehicle) vehicle(Sent(log_.back()));  // a copy: the script may send (and grow the log)
    return true;
  }

 private:
  EventLoop& loop_;
  std::vector<Sent> log_;
};

// A host-clock loop for one test.
inline std::unique_ptr<EventLoop> make_loop() {
  auto l = EventLoop::create(LoopConfig::host());
  EXPECT_TRUE(l) << (l ? "" : l.message());
  return std::move(*l);
}

// The decoded message, when s is one.
template <class Msg>
std::optional<Msg> as(const FakeMavPort::Sent& s) {
  if (s.msgid != Msg::kId) return std::nullopt;
  return Msg::decode(s.payload.data());
}

}  // namespace uavsim::client::testing
