// Small blocking-with-timeout socket helpers (wall clock). Library internal.
#pragma once

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

}  // namespace uavsim::client::net
