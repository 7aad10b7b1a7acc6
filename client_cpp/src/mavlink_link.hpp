// MavlinkLink: the Vehicle's link to one vehicle. It owns the socket (TCP, UDP to a vehicle, or UDP
// listening for one), the MAVLink parser and the sequence numbers, sends the GCS heartbeat, picks
// the vehicle (the first autopilot heard, or config.target_sysid) and hands that vehicle's frames
// to the units' handlers (MavPort). Under lockstep it is a sequence source of the loop (`done`
// names the last seq it sent) and, pipelined, holds what it sends during a tick's work until the
// next tick.
//
// Library internal; loop thread only.
#pragma once

#include <cstdint>
#include <functional>
#include <string>

#include "mav_port.hpp"
#include "uavsim/client/event_loop.hpp"
#include "uavsim/client/vehicle.hpp"
#include "uavsim/common/mavlink/parser.hpp"

namespace uavsim::client {

class MavlinkLink final : public MavPort {
 public:
  MavlinkLink(EventLoop& loop, const VehicleConfig& config);
  ~MavlinkLink() override;
  MavlinkLink(const MavlinkLink&) = delete;
  MavlinkLink& operator=(const MavlinkLink&) = delete;

  // Closes any open link, then opens one to address ("tcp:HOST:PORT", "HOST:PORT", "udp:HOST:PORT",
  // "udpin:ADDR:PORT"), forgets the vehicle it had picked and starts the heartbeat.
  // kInvalidArgument for a bad address; the socket's failure (TCP: kConnectionRefused, kTimeout
  // after timeout_s).
  Result<void> open(const std::string& address, double timeout_s);
  // Closes the link; why (nullptr: closed on purpose) is logged when it was open. The on_closed
  // callback runs either way.
  void close(const char* why);
  // Runs after every close, with its reason (nullptr: on purpose).
  void on_closed(std::function<void(const char* why)> fn) { on_closed_ = std::move(fn); }

  bool is_open() const override { return fd_ >= 0; }
  std::uint8_t target_sysid() const override { return target_sysid_; }
  std::uint8_t target_compid() const override { return target_compid_; }
  const std::string& address() const override { return address_; }

 protected:
  bool send_payload(const common::mavlink::MessageInfo& info,
                    std::span<const std::uint8_t> full_payload) override;

 private:
  void flush();
  void release_held();
  void on_io(std::uint32_t what);
  void handle(const common::mavlink::Frame& f);
  void send_heartbeat();

  EventLoop& loop_;
  const VehicleConfig& config_;
  int fd_ = -1;
  std::string address_;
  bool udp_ = false;       // a UDP link: datagrams, no end of stream
  bool udp_peer_ = false;  // the UDP socket is connected to the vehicle (udpin: once it has sent)
  common::mavlink::Parser parser_;
  std::string out_;       // bytes not yet accepted by the socket
  std::string held_out_;  // pipelined lockstep: frames sent during this tick's work (release_held)
  std::uint8_t seq_ = 0;
  bool sent_any_ = false;
  std::uint8_t last_seq_ = 0;
  std::uint8_t target_sysid_ = 0;
  std::uint8_t target_compid_ = 1;
  TimerId heartbeat_timer_ = 0;
  std::uint64_t seq_source_ = 0;
  std::uint64_t output_flusher_ = 0;
  std::function<void(const char*)> on_closed_;
};

}  // namespace uavsim::client
