// configure_accepted_tcp: the options land on a real accepted loopback connection.
#include "uavsim/common/tcp_socket.hpp"

#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <unistd.h>

namespace uavsim::common {
namespace {

int get_int(int fd, int level, int name) {
  int v = -1;
  socklen_t n = sizeof(v);
  EXPECT_EQ(getsockopt(fd, level, name, &v, &n), 0);
  return v;
}

TEST(TcpSocket, AcceptedConnectionGetsNoDelayAndKeepaliveTiming) {
  const int listener = socket(AF_INET, SOCK_STREAM, 0);
  ASSERT_GE(listener, 0);
  sockaddr_in sa{};
  sa.sin_family = AF_INET;
  sa.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  ASSERT_EQ(bind(listener, reinterpret_cast<sockaddr*>(&sa), sizeof(sa)), 0);
  ASSERT_EQ(listen(listener, 1), 0);
  socklen_t len = sizeof(sa);
  ASSERT_EQ(getsockname(listener, reinterpret_cast<sockaddr*>(&sa), &len), 0);
  const int client = socket(AF_INET, SOCK_STREAM, 0);
  ASSERT_EQ(connect(client, reinterpret_cast<sockaddr*>(&sa), sizeof(sa)), 0);
  const int accepted = accept(listener, nullptr, nullptr);
  ASSERT_GE(accepted, 0);
  EXPECT_EQ(get_int(accepted, SOL_SOCKET, SO_KEEPALIVE), 0);  // off until configured

  EXPECT_TRUE(configure_accepted_tcp(accepted, TcpKeepalive{30, 5, 4}));
  EXPECT_NE(get_int(accepted, IPPROTO_TCP, TCP_NODELAY), 0);
  EXPECT_NE(get_int(accepted, SOL_SOCKET, SO_KEEPALIVE), 0);
  EXPECT_EQ(get_int(accepted, IPPROTO_TCP, TCP_KEEPIDLE), 30);
  EXPECT_EQ(get_int(accepted, IPPROTO_TCP, TCP_KEEPINTVL), 5);
  EXPECT_EQ(get_int(accepted, IPPROTO_TCP, TCP_KEEPCNT), 4);
  // the defaults: a vanished peer is dropped within 60 + 3 x 10 s of silence
  EXPECT_TRUE(configure_accepted_tcp(accepted));
  EXPECT_EQ(get_int(accepted, IPPROTO_TCP, TCP_KEEPIDLE), 60);
  EXPECT_EQ(get_int(accepted, IPPROTO_TCP, TCP_KEEPCNT), 3);
  close(accepted);
  close(client);
  close(listener);
}

TEST(TcpSocket, ABadDescriptorIsReportedNotFatal) { EXPECT_FALSE(configure_accepted_tcp(-1)); }

}  // namespace
}  // namespace uavsim::common
