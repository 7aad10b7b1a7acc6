// Options every accepted TCP connection of the server gets (MAVLink endpoints and the sim API).
#pragma once

#include <netinet/in.h>
#include <netinet/tcp.h>
#include <sys/socket.h>

namespace uavsim::common {

// TCP keepalive timing: a peer silent this long is probed, and dropped after the probes go unanswered.
// A ground station or mission host that vanishes without a FIN or RST (power loss, a cable pulled, a
// NAT forgetting the flow) would otherwise hold its connection, buffers and a client slot for ever.
struct TcpKeepalive {
  int idle_s = 60;      // silence before the first probe
  int interval_s = 10;  // between probes
  int probes = 3;       // unanswered probes before the kernel closes the connection
};

// No Nagle delay (telemetry and replies are small and latency-bound) and keepalive as above. Returns
// false if the kernel refused an option; the connection is usable either way.
inline bool configure_accepted_tcp(int fd, const TcpKeepalive& k = {}) {
  const int one = 1;
  bool ok = setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof(one)) == 0;
  ok = setsockopt(fd, SOL_SOCKET, SO_KEEPALIVE, &one, sizeof(one)) == 0 && ok;
  ok = setsockopt(fd, IPPROTO_TCP, TCP_KEEPIDLE, &k.idle_s, sizeof(k.idle_s)) == 0 && ok;
  ok = setsockopt(fd, IPPROTO_TCP, TCP_KEEPINTVL, &k.interval_s, sizeof(k.interval_s)) == 0 && ok;
  ok = setsockopt(fd, IPPROTO_TCP, TCP_KEEPCNT, &k.probes, sizeof(k.probes)) == 0 && ok;
  return ok;
}

}  // namespace uavsim::common
