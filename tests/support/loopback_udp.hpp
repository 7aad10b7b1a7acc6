// A UDP socket on the loopback interface at a port the kernel picks, for tests that stand in for a
// ground station or a vehicle's UDP peer.
#pragma once

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>

#include <cstdint>

namespace uavsim::testing {

// Opens a UDP socket (flags, e.g. SOCK_NONBLOCK, OR-ed into its type; close-on-exec always) bound
// to 127.0.0.1 at an ephemeral port; returns its descriptor and puts the port in *port.
inline int bind_loopback_udp(std::uint16_t* port, int flags = 0) {
  const int fd = ::socket(AF_INET, SOCK_DGRAM | SOCK_CLOEXEC | flags, 0);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  ::bind(fd, reinterpret_cast<sockaddr*>(&a), sizeof(a));
  socklen_t len = sizeof(a);
  ::getsockname(fd, reinterpret_cast<sockaddr*>(&a), &len);
  *port = ntohs(a.sin_port);
  return fd;
}

}  // namespace uavsim::testing
