// A TCP connection to a server of the test's own on the loopback interface (the sim API, a
// LineServer), for tests and harnesses that speak to it as a raw client.
#pragma once

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>

#include <cstdint>

namespace uavsim::testing {

// Connects the TCP socket fd to 127.0.0.1:port; true once connected.
inline bool connect_loopback_tcp(int fd, std::uint16_t port) {
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_port = htons(port);
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  return ::connect(fd, reinterpret_cast<sockaddr*>(&a), sizeof(a)) == 0;
}

}  // namespace uavsim::testing
