// CommandSender: COMMAND_LONG with its COMMAND_ACK, the one retry machine of the Vehicle. A command
// is sent at once and re-sent on silence (config.command_attempts attempts of command_timeout_s
// each, the attempt number in `confirmation`); IN_PROGRESS waits one more period for the final ack.
// The blocking form is the non-blocking one plus a wait on the loop (as MAVSDK's arm() wraps
// arm_async()), so both behave alike by construction.
//
// Library internal; loop thread only.
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <map>
#include <string>

#include "mav_port.hpp"
#include "uavsim/client/event_loop.hpp"
#include "uavsim/client/result.hpp"
#include "uavsim/client/vehicle.hpp"
#include "uavsim/common/mavlink/generated/enums.hpp"

namespace uavsim::client {

// "NAV_TAKEOFF", or "MAV_CMD 12345" for a number the dialect does not name.
std::string command_name(std::uint16_t command);

class CommandSender {
 public:
  using Params = std::array<float, 7>;
  using Done = std::function<void(Result<void>)>;

  // Handles COMMAND_ACK on port. config must outlive the sender.
  CommandSender(EventLoop& loop, MavPort& port, const VehicleConfig& config);
  ~CommandSender();  // pending commands end silently
  CommandSender(const CommandSender&) = delete;
  CommandSender& operator=(const CommandSender&) = delete;

  // Sends command now; done (optional) runs posted to the loop with the outcome: ok, the vehicle's
  // refusal (kDenied, kFailed, ... with the MAV_RESULT), kTimeout after the last attempt,
  // kConnectionLost, kNotConnected, or kCancelled when a command with the same id replaces it.
  void send_async(std::uint16_t command, const Params& params, Done done);
  void send_async(common::mavlink::MavCmd command, const Params& params, Done done);
  // The same command, waiting on the loop for its outcome; also kConnectionLost when the lockstep
  // clock is lost meanwhile.
  Result<void> send(std::uint16_t command, const Params& params);
  Result<void> send(common::mavlink::MavCmd command, const Params& params);

  // Ends every pending command with kConnectionLost ("<COMMAND>: <why>").
  void fail_all(const std::string& why);
  // Forgets every pending command without calling its done.
  void drop_all();

 private:
  struct Pending {
    Params params{};
    int attempt = 0;
    TimerId retry = 0;
    Done done;
    std::uint64_t serial = 0;  // which send_async() made it
  };
  void transmit(std::uint16_t command);
  void arm_retry(std::uint16_t command);
  void on_ack(const common::mavlink::Frame& f);
  // ends a pending command (nothing when none): its done runs on the loop, after the caller's own
  // work, so a done that sends the next command does not nest inside the I/O handler
  void finish(std::uint16_t command, Result<void> outcome);
  Result<void> no_ack(std::uint16_t command) const;

  EventLoop& loop_;
  MavPort& port_;
  const VehicleConfig& config_;
  std::map<std::uint16_t, Pending> pending_;
  std::uint64_t next_serial_ = 1;
};

}  // namespace uavsim::client
