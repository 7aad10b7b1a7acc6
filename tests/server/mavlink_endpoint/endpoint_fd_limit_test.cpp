// Out of file descriptors: the TCP listener neither spins nor stays stuck once descriptors are back.
#include <sys/socket.h>

#include "../../support/fd_exhaustion.hpp"
#include "test_gcs.hpp"

namespace uavsim::server::mavlink::testing {
namespace {

using uavsim::testing::FdExhaustion;

// A connection that arrives while the process has no descriptor left would keep the level-triggered
// listener readable and the I/O thread spinning; it is accepted on the spare descriptor and closed at once
// (the peer reads the end of the stream), and clients connect as before once descriptors are free.
TEST_F(EndpointTest, AConnectionWithNoDescriptorLeftIsClosedNotSpunOn) {
  // the I/O thread is running (a ground station accepted) before the process runs out: under UBSan
  // the vptr check of a thread's first call probes memory through a pipe, which needs descriptors
  const auto first = connect();
  // the client's socket exists before the process runs out
  const int client = socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
  ASSERT_GE(client, 0);
  sockaddr_in sa{};
  sa.sin_family = AF_INET;
  sa.sin_port = htons(server_->port(0));
  sa.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  {
    FdExhaustion no_fds;
    ASSERT_TRUE(no_fds.exhausted());
    // the handshake completes in the listen backlog, without the server accepting
    ASSERT_EQ(::connect(client, reinterpret_cast<sockaddr*>(&sa), sizeof(sa)), 0);
    EXPECT_TRUE(wait_for([&] { return server_->stats(0).fd_exhausted_accepts >= 1; }));
    pollfd p{client, POLLIN, 0};
    ASSERT_EQ(poll(&p, 1, 5000), 1) << "the waiting connection was never closed";
    char byte = 0;
    EXPECT_LE(recv(client, &byte, 1, 0), 0);
  }
  close(client);
  EXPECT_EQ(server_->stats(0).clients_accepted, 1u);
  EXPECT_EQ(server_->stats(0).fd_exhausted_accepts, 1u);

  // descriptors are back: a ground station connects and is answered (31000: no such command)
  auto g = connect();
  EXPECT_EQ(server_->client_count(0), 2u);  // the first one and this
  EXPECT_EQ(command(*g, kUnsupportedCmd), 3);  // MAV_RESULT_UNSUPPORTED
}

}  // namespace
}  // namespace uavsim::server::mavlink::testing
