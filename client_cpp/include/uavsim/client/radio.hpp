// A2aRadio: a vehicle's air-to-air radio (IEEE 802.15.4 frames of 1-127 bytes, seed 6.2; the
// simulator's channel may allow fewer, or up to 1500 on 802.11: max_frame_bytes()), as a
// drone's onboard computer drives its radio module. In the simulator it is the server's radio
// (docs/protocol.md "Radio"), carried on the loop's lockstep connection: a frame that arrives at
// sim time t is received before the tick at or after t, in the same order in every run, so a
// program that reads its frames at each tick sees the same frames at the same tick every time.
//
// Needs the lockstep clock (the subscription rides on the loop's simulator connection); on a real
// drone a radio driver would offer the same send / take_received.
//
// Loop-thread only, like everything on an EventLoop.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <vector>

#include "uavsim/client/event_loop.hpp"
#include "uavsim/client/result.hpp"

namespace uavsim::client {

// 802.15.4's whole PSDU: the frame size of a server that does not say its channel's
inline constexpr std::size_t kRadioMaxFrameBytes = 127;
// The largest frame any channel of the simulator carries (802.11 on its ns3 backend)
inline constexpr std::size_t kRadioLargestFrameBytes = 1500;

struct RadioFrame {
  double time_s = 0.0;  // arrival (sim time)
  int from = -1;        // sender's vehicle index
  bool broadcast = true;
  std::vector<std::uint8_t> data;
};

struct RadioCounters {
  std::uint64_t sent = 0;      // frames handed to the radio
  std::uint64_t refused = 0;   // frames the radio refused (queue full, ...)
  std::uint64_t received = 0;  // frames received
};

class A2aRadio {
 public:
  // Opens vehicle's radio (its index in the simulator) and waits for the subscription's answer
  // (timeout_s on the loop clock). kUnsupported on the host clock; kDenied with the simulator's
  // message for an unknown vehicle.
  static Result<std::unique_ptr<A2aRadio>> open(EventLoop& loop, int vehicle,
                                                double timeout_s = 10.0);
  ~A2aRadio();  // unsubscribes
  A2aRadio(const A2aRadio&) = delete;
  A2aRadio& operator=(const A2aRadio&) = delete;

  int vehicle() const;
  // The largest frame the simulator's radio channel carries, bytes: 127 on its simple backend, 116
  // on ns3's 802.15.4 (its 127-byte PSDU less the MAC header and FCS the channel accounts for),
  // 1500 on ns3's 802.11.
  std::size_t max_frame_bytes() const;
  // Puts a frame on air: to every vehicle in range (to < 0) or to one vehicle. Does not wait for
  // the simulator's answer (a refusal is counted in counters().refused). kInvalidArgument for an
  // empty frame or one over max_frame_bytes(); kConnectionLost without a simulator connection.
  Result<void> send(const std::vector<std::uint8_t>& data, int to = -1);
  // The frames received since the last call, in order of arrival.
  std::vector<RadioFrame> take_received();
  const RadioCounters& counters() const;

 private:
  struct Impl;
  explicit A2aRadio(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace uavsim::client
