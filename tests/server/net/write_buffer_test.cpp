// The bounded write buffer: the bound, partial writes in order, a failed socket.
#include "net/write_buffer.hpp"

#include <gtest/gtest.h>
#include <sys/socket.h>
#include <unistd.h>

#include <string>

namespace uavsim::server::net {
namespace {

class WriteBufferOnSocket : public ::testing::Test {
 protected:
  void SetUp() override {
    ASSERT_EQ(socketpair(AF_UNIX, SOCK_STREAM | SOCK_NONBLOCK, 0, fds_), 0);
    // a small kernel buffer, so that a few kilobytes are a partial write
    const int small = 4096;
    setsockopt(fds_[0], SOL_SOCKET, SO_SNDBUF, &small, sizeof(small));
    setsockopt(fds_[1], SOL_SOCKET, SO_RCVBUF, &small, sizeof(small));
  }
  void TearDown() override {
    if (fds_[0] >= 0) close(fds_[0]);
    if (fds_[1] >= 0) close(fds_[1]);
  }
  // everything readable at the peer now
  std::string drain_peer() {
    std::string got;
    char buf[65536];
    for (ssize_t n; (n = read(fds_[1], buf, sizeof(buf))) > 0;)
      got.append(buf, static_cast<size_t>(n));
    return got;
  }
  int fds_[2] = {-1, -1};
};

TEST(WriteBuffer, RefusesWhatWouldPassTheBoundWholeAndTakesNothingAfterClose) {
  WriteBuffer b(10);
  EXPECT_EQ(b.append("123456"), WriteBuffer::Append::kQueued);
  EXPECT_EQ(b.append("12345"), WriteBuffer::Append::kFull);  // 11 > 10: refused whole
  EXPECT_EQ(b.append("1234"), WriteBuffer::Append::kQueued);
  EXPECT_EQ(b.unwritten(), 10u);
  b.append_unbounded("bye\n");  // a last message may pass the bound
  EXPECT_EQ(b.unwritten(), 14u);
  b.close();
  EXPECT_EQ(b.unwritten(), 0u);
  EXPECT_EQ(b.append("x"), WriteBuffer::Append::kClosed);
}

TEST_F(WriteBufferOnSocket, PartialWritesArriveWholeAndInOrder) {
  std::string sent;
  for (int k = 0; k < 2000; ++k) sent += "message " + std::to_string(k) + "\n";  // ~25 kB
  WriteBuffer b(1 << 20);
  ASSERT_EQ(b.append(sent.substr(0, sent.size() / 2)), WriteBuffer::Append::kQueued);
  std::size_t written = 0;
  ASSERT_EQ(b.write_to(fds_[0], &written), WriteBuffer::Write::kBlocked);
  ASSERT_LT(written, sent.size() / 2);
  EXPECT_EQ(b.unwritten(), sent.size() / 2 - written);
  // more queued while the first batch is stuck in the socket
  ASSERT_EQ(b.append(sent.substr(sent.size() / 2)), WriteBuffer::Append::kQueued);
  std::string got;
  for (int round = 0; round < 10000 && got.size() < sent.size(); ++round) {
    got += drain_peer();
    const WriteBuffer::Write w = b.write_to(fds_[0], &written);
    ASSERT_NE(w, WriteBuffer::Write::kFailed);
  }
  got += drain_peer();
  EXPECT_EQ(got, sent);
  EXPECT_EQ(written, sent.size());
  EXPECT_EQ(b.unwritten(), 0u);
  EXPECT_FALSE(b.has_queued());
}

// the bound counts the bytes stuck in the socket's batch too: a peer that stops reading cannot make
// the server hold more than the bound
TEST_F(WriteBufferOnSocket, BytesStuckInTheSocketCountAgainstTheBound) {
  const std::size_t kBound = 64 * 1024;
  WriteBuffer b(kBound);
  ASSERT_EQ(b.append(std::string(kBound, 'a')), WriteBuffer::Append::kQueued);
  std::size_t written = 0;
  ASSERT_EQ(b.write_to(fds_[0], &written), WriteBuffer::Write::kBlocked);
  const std::size_t stuck = kBound - written;
  EXPECT_EQ(b.unwritten(), stuck);
  EXPECT_EQ(b.append(std::string(written + 1, 'b')), WriteBuffer::Append::kFull);
  EXPECT_EQ(b.append(std::string(written, 'b')), WriteBuffer::Append::kQueued);
}

TEST_F(WriteBufferOnSocket, AClosedPeerFailsTheWriteWithoutASignal) {
  close(fds_[1]);
  fds_[1] = -1;
  WriteBuffer b(1024);
  ASSERT_EQ(b.append("hello\n"), WriteBuffer::Append::kQueued);
  std::size_t written = 0;
  EXPECT_EQ(b.write_to(fds_[0], &written), WriteBuffer::Write::kFailed);  // EPIPE, no SIGPIPE
  EXPECT_EQ(written, 0u);
}

TEST(WriteBuffer, TakeQueuedHandsTheBytesToADatagramWriter) {
  WriteBuffer b(1024);
  ASSERT_EQ(b.append("ab"), WriteBuffer::Append::kQueued);
  ASSERT_EQ(b.append("cd"), WriteBuffer::Append::kQueued);
  std::string out = "stale";
  b.take_queued(out);
  EXPECT_EQ(out, "abcd");
  EXPECT_EQ(b.unwritten(), 0u);
  EXPECT_FALSE(b.has_queued());
}

}  // namespace
}  // namespace uavsim::server::net
