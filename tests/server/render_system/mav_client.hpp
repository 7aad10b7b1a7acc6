// A minimal MAVLink sender for the system tests: a TCP client of a vehicle endpoint that encodes messages
// with the project's codec and never reads (the endpoint drops what a non-reader does not take).
#pragma once

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <array>
#include <cstring>
#include <string>

#include "uavsim/common/mavlink/codec.hpp"
#include "uavsim/common/mavlink/generated/messages.hpp"

namespace uavsim::server::render::testing {

class MavClient {
 public:
  explicit MavClient(uint16_t port) {
    fd_ = socket(AF_INET, SOCK_STREAM, 0);
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_port = htons(port);
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    connected_ = connect(fd_, reinterpret_cast<sockaddr*>(&a), sizeof(a)) == 0;
  }
  ~MavClient() { close(fd_); }
  bool connected() const { return connected_; }
  // sends one message; returns its sequence number
  template <class Msg>
  uint8_t send(const Msg& m) {
    common::mavlink::FrameHeader h;
    h.sysid = 255;
    h.compid = 190;
    h.seq = seq_;
    const common::mavlink::EncodedFrame f = common::mavlink::encode(h, m);
    const auto v = f.view();
    size_t off = 0;
    while (off < v.size()) {
      const ssize_t n = ::send(fd_, v.data() + off, v.size() - off, MSG_NOSIGNAL);
      if (n <= 0) break;
      off += static_cast<size_t>(n);
    }
    return seq_++;
  }
  uint8_t command(uint16_t cmd, std::array<float, 7> p = {}) {
    common::mavlink::msg::CommandLong c;
    c.command = cmd;
    c.target_system = 1;
    c.target_component = 1;
    c.param1 = p[0], c.param2 = p[1], c.param3 = p[2], c.param4 = p[3];
    c.param5 = p[4], c.param6 = p[5], c.param7 = p[6];
    return send(c);
  }
  uint8_t heartbeat() {
    common::mavlink::msg::Heartbeat hb;
    hb.type = 6;        // MAV_TYPE_GCS
    hb.autopilot = 8;   // MAV_AUTOPILOT_INVALID
    return send(hb);
  }
  uint8_t param_set(const std::string& name, float value) {
    common::mavlink::msg::ParamSet p;
    p.target_system = 1;
    p.target_component = 1;
    std::memcpy(p.param_id.data(), name.data(), std::min<size_t>(16, name.size()));
    p.param_value = value;
    p.param_type = 9;  // MAV_PARAM_TYPE_REAL32
    return send(p);
  }

 private:
  int fd_ = -1;
  bool connected_ = false;
  uint8_t seq_ = 0;
};

}  // namespace uavsim::server::render::testing
