// The acceptor: connections handed over, and no spin when the process is out of descriptors.
#include "net/tcp_acceptor.hpp"

#include <gtest/gtest.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <future>
#include <stdexcept>

#include "../../support/fd_exhaustion.hpp"

namespace uavsim::server::net {
namespace {

// a blocking client socket connected to 127.0.0.1:port (-1 on failure)
int connect_to(std::uint16_t port) {
  const int fd = socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
  sockaddr_in sa{};
  if (fd < 0 || !ipv4_address("127.0.0.1", port, &sa)) return -1;
  if (connect(fd, reinterpret_cast<sockaddr*>(&sa), sizeof(sa)) != 0) {
    close(fd);
    return -1;
  }
  return fd;
}

// waits (blocking in poll, not sleeping) until the server side closed fd: true on end of stream
bool closed_by_server(int fd) {
  pollfd p{fd, POLLIN, 0};
  if (poll(&p, 1, 10000) != 1) return false;
  char byte = 0;
  return recv(fd, &byte, 1, 0) <= 0;
}

TEST(TcpAcceptor, HandsEachConnectionToItsOwner) {
  EventLoop loop;
  FdReserve reserve;
  std::promise<std::string> peer;
  TcpAcceptor acceptor(loop, reserve, "127.0.0.1", 0, 16, "test",
                       [&](int fd, const sockaddr_in& from) {
                         close(fd);
                         peer.set_value(address_text(from));
                       });
  ASSERT_NE(acceptor.port(), 0);
  acceptor.start();
  loop.start();
  const int client = connect_to(acceptor.port());
  ASSERT_GE(client, 0);
  EXPECT_EQ(peer.get_future().get().rfind("127.0.0.1:", 0), 0u);
  EXPECT_TRUE(closed_by_server(client));
  close(client);
  loop.stop();
}

TEST(TcpAcceptor, ABadAddressOrABusyPortIsAStartupErrorNamingIt) {
  EventLoop loop;
  FdReserve reserve;
  auto ignore = [](int fd, const sockaddr_in&) { close(fd); };
  try {
    TcpAcceptor a(loop, reserve, "localhost", 0, 16, "test", ignore);
    FAIL() << "a host name is not an IPv4 address";
  } catch (const std::runtime_error& e) {
    EXPECT_STREQ(e.what(), "test: bad bind address 'localhost' (an IPv4 address)");
  }
  TcpAcceptor first(loop, reserve, "127.0.0.1", 0, 16, "test", ignore);
  const std::string where = "127.0.0.1:" + std::to_string(first.port());
  try {
    TcpAcceptor second(loop, reserve, "127.0.0.1", first.port(), 16, "test", ignore);
    FAIL() << "the port is taken";
  } catch (const std::runtime_error& e) {
    EXPECT_EQ(std::string(e.what()).rfind("test: cannot listen on " + where + ": ", 0), 0u)
        << e.what();
  }
}

// A connection that arrives while the process has no descriptor left would keep the level-triggered
// listener readable and the loop spinning: it is accepted on the reserve and closed at once, and
// connections are handed over as before once descriptors are free.
TEST(TcpAcceptor, AConnectionWithNoDescriptorLeftIsClosedOnTheReserve) {
  EventLoop loop;
  FdReserve reserve;
  int accepted = 0;  // I/O thread
  TcpAcceptor acceptor(loop, reserve, "127.0.0.1", 0, 16, "test", [&](int fd, const sockaddr_in&) {
    ++accepted;
    close(fd);
  });
  acceptor.start();
  loop.start();
  // one connection while descriptors last: the loop's dispatch runs once before they run out.
  // (UBSan's vptr check opens a pipe the first time it meets a type — here the handler's shared
  // control block — and with no descriptor left it reports a valid object as invalid.)
  const int first = connect_to(acceptor.port());
  ASSERT_GE(first, 0);
  EXPECT_TRUE(closed_by_server(first));
  close(first);
  // the client's socket exists before the process runs out
  const int client = socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
  ASSERT_GE(client, 0);
  sockaddr_in sa{};
  ASSERT_TRUE(ipv4_address("127.0.0.1", acceptor.port(), &sa));
  {
    uavsim::testing::FdExhaustion no_fds;
    ASSERT_TRUE(no_fds.exhausted());
    // the handshake completes in the listen backlog, without the server accepting
    ASSERT_EQ(connect(client, reinterpret_cast<sockaddr*>(&sa), sizeof(sa)), 0);
    EXPECT_TRUE(closed_by_server(client)) << "the waiting connection was never closed";
  }
  close(client);
  int seen = -1;
  loop.call([&] { seen = accepted; });
  EXPECT_EQ(seen, 1);  // the first connection only
  EXPECT_EQ(acceptor.exhausted_accepts(), 1u);

  // descriptors are back: the next connection reaches the owner
  const int next = connect_to(acceptor.port());
  ASSERT_GE(next, 0);
  EXPECT_TRUE(closed_by_server(next));
  close(next);
  loop.call([&] { seen = accepted; });
  EXPECT_EQ(seen, 2);
  EXPECT_EQ(acceptor.exhausted_accepts(), 1u);
  loop.stop();
}

}  // namespace
}  // namespace uavsim::server::net
