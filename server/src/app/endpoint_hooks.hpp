// The MAVLink endpoint's fault and lockstep hooks as the sim API sees them: link drop, "has the
// endpoint handled this sequence number", and "flush what is queued before a tick". uavsim-server wires
// them in server_app.cpp; tests that assemble a server in-process use the same class.
#pragma once

#include <cstddef>
#include <cstdint>

#include "api/api_server.hpp"
#include "mavlink/endpoint.hpp"

namespace uavsim::server::app {

class EndpointHooks : public api::LinkControl, public api::SeqWaiter {
 public:
  explicit EndpointHooks(mavlink::MavlinkServer& server) : server_(server) {}
  // Thread contracts are MavlinkServer's: called on the loop thread.
  bool set_link_down(std::size_t vehicle, bool down) override {
    return server_.set_link_down(vehicle, down);
  }
  bool seq_processed(std::size_t vehicle, std::uint8_t seq) const override {
    return server_.seq_processed(vehicle, seq);
  }
  void flush_sent() override { server_.flush_queued(); }
  void set_progress_listener(std::function<void()> listener) override {
    server_.set_seq_listener(std::move(listener));
  }

 private:
  mavlink::MavlinkServer& server_;
};

}  // namespace uavsim::server::app
