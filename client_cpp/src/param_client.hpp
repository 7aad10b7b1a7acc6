// ParamClient: reading and writing the vehicle's parameters by name (PARAM_REQUEST_READ and
// PARAM_SET, both answered with PARAM_VALUE). A request is re-sent each second until the value
// arrives or the timeout ends; ArduPilot ignores an unknown name silently, so that is a timeout.
//
// Library internal; loop thread only.
#pragma once

#include <cstdint>
#include <map>
#include <string>

#include "mav_port.hpp"
#include "uavsim/client/event_loop.hpp"
#include "uavsim/client/result.hpp"

namespace uavsim::client {

class ParamClient {
 public:
  // Handles PARAM_VALUE on port.
  ParamClient(EventLoop& loop, MavPort& port);
  ParamClient(const ParamClient&) = delete;
  ParamClient& operator=(const ParamClient&) = delete;

  // The parameter's value, waiting on the loop at most timeout_s: kNotConnected, kInvalidArgument
  // (names have 1-16 characters), kTimeout (with the name), kConnectionLost.
  Result<float> get(const std::string& name, double timeout_s);
  // Sets it (as the type the vehicle last reported for it, else REAL32) and returns the value the
  // vehicle echoes: also kInvalidArgument for a non-finite value and kDenied when the vehicle kept
  // another value.
  Result<float> set(const std::string& name, float value, double timeout_s);

 private:
  struct Seen {
    float value = 0;
    std::uint8_t type = 0;
    std::uint64_t count = 0;  // PARAM_VALUEs heard for this name
  };
  // sends request until a PARAM_VALUE for name arrives (true), or the link closes or the time ends
  template <class Request>
  bool ask(const std::string& name, const Request& request, double timeout_s);

  EventLoop& loop_;
  MavPort& port_;
  std::map<std::string, Seen> seen_;
};

}  // namespace uavsim::client
