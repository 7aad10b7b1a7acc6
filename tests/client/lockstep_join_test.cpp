// Joining the lockstep clock against a scripted sim API peer on loopback: what the client's clock
// reads after the join, whatever way the server's bytes are cut into reads.
#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <nlohmann/json.hpp>
#include <string>
#include <thread>

#include "uavsim/client/event_loop.hpp"

namespace uavsim::client {
namespace {

constexpr double kTimeTol_s = 1e-9;

// A one-connection peer that speaks just enough of the sim API to be joined: a hello offering no
// shared memory, then, for the join request, its reply and the first tick in one write (as a server
// under load, or one that answers fast, delivers them: one read sees both).
class JoinPeer {
 public:
  JoinPeer() {
    listen_fd_ = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
    sockaddr_in addr{};
    addr.sin_family = AF_INET;
    addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    socklen_t len = sizeof(addr);
    if (::bind(listen_fd_, reinterpret_cast<sockaddr*>(&addr), len) != 0 ||
        ::listen(listen_fd_, 1) != 0 ||
        ::getsockname(listen_fd_, reinterpret_cast<sockaddr*>(&addr), &len) != 0) {
      return;
    }
    port_ = ntohs(addr.sin_port);
    thread_ = std::thread([this] { serve(); });
  }
  ~JoinPeer() {
    if (thread_.joinable()) thread_.join();
    if (listen_fd_ >= 0) ::close(listen_fd_);
  }
  int port() const { return port_; }

  static constexpr double kFirstTickTime_s = 18.38;
  static constexpr double kPeriod_s = 0.02;

 private:
  void serve() {
    const int fd = ::accept(listen_fd_, nullptr, nullptr);
    if (fd < 0) return;
    send_all(fd, "{\"hello\":\"uavsim\",\"protocol\":1,\"ops\":[\"lockstep_join\",\"done\"]}\n");
    const nlohmann::json join = nlohmann::json::parse(read_line(fd), nullptr, false);
    if (join.is_object() && join.value("op", std::string()) == "lockstep_join") {
      const nlohmann::json reply = {
          {"id", join["id"]},
          {"ok", true},
          {"result",
           {{"first_tick_time", kFirstTickTime_s}, {"period_s", kPeriod_s}, {"timeout_s", 10.0}}}};
      const nlohmann::json tick = {{"event", "tick"}, {"tick", 919}, {"time", kFirstTickTime_s}};
      send_all(fd, reply.dump() + "\n" + tick.dump() + "\n");
    }
    // until the client closes: its done and whatever follows are read and dropped
    char buf[4096];
    while (::read(fd, buf, sizeof(buf)) > 0) {
    }
    ::close(fd);
  }
  static void send_all(int fd, const std::string& bytes) {
    for (size_t sent = 0; sent < bytes.size();) {
      const ssize_t n = ::send(fd, bytes.data() + sent, bytes.size() - sent, MSG_NOSIGNAL);
      if (n <= 0) return;
      sent += static_cast<size_t>(n);
    }
  }
  static std::string read_line(int fd) {
    std::string line;
    char c = 0;
    while (::read(fd, &c, 1) == 1 && c != '\n') line += c;
    return line;
  }

  int listen_fd_ = -1;
  int port_ = 0;
  std::thread thread_;
};

TEST(LockstepJoin, TheFirstTickReadWithTheJoinsReplySetsTheClock) {
  JoinPeer peer;
  ASSERT_GT(peer.port(), 0);
  LoopConfig config = LoopConfig::lockstep("127.0.0.1", peer.port(), JoinPeer::kPeriod_s);
  config.lockstep_transport = LoopConfig::Transport::kTcp;
  auto loop = EventLoop::create(config);
  ASSERT_TRUE(loop) << loop.message();
  // the tick came in the same read as the reply: the clock is at the tick, not one period before
  // it (the time the reply announces for the moment before the first tick)
  EXPECT_NEAR((*loop)->now(), JoinPeer::kFirstTickTime_s, kTimeTol_s);
}

}  // namespace
}  // namespace uavsim::client
