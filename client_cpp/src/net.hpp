// Small blocking-with-timeout socket helpers (wall clock). Library internal.
#pragma once

#include <optional>
#include <string>

#include "uavsim/client/result.hpp"

namespace uavsim::client::net {

// Connects a TCP socket (non-blocking afterwards, TCP_NODELAY, close-on-exec). kConnectionRefused when
// nothing listens, kTimeout after timeout_s, kInvalidArgument for an unresolvable host.
Result<int> tcp_connect(const std::string& host, int port, double timeout_s);
// Writes all of data; false on error or after timeout_s without progress.
bool send_all(int fd, const std::string& data, double timeout_s);
bool send_all(int fd, const void* data, std::size_t size, double timeout_s);
// The next '\n'-terminated line (without it), buffering extra bytes in buf.
Result<std::string> read_line(int fd, std::string& buf, double timeout_s);
// "tcp:HOST:PORT", "HOST:PORT" or ":PORT" / "PORT" (loopback) => host, port.
bool parse_address(const std::string& address, std::string* host, int* port);

// A MAVLink link's address, as MAVProxy and mavlink-router write them:
//   tcp:HOST:PORT (or HOST:PORT)   connect to a TCP endpoint
//   udp:HOST:PORT                  send datagrams to a vehicle listening there, hear its answers
//   udpin:ADDR:PORT                listen there; the first peer that sends is the vehicle
struct LinkAddress {
  enum class Kind { kTcp, kUdp, kUdpIn };
  Kind kind = Kind::kTcp;
  std::string host;
  int port = 0;
};
std::optional<LinkAddress> parse_link_address(const std::string& address);
// A non-blocking UDP socket: connected to host:port (udp:), or bound to it (udpin:). kInvalidArgument for
// an unresolvable host, kIo when the port cannot be bound.
Result<int> udp_open(const std::string& host, int port, bool listen);

}  // namespace uavsim::client::net
