// A running server for API tests: a world, its objects, a Runner on its own thread (as fast as possible)
// with the API's gate; and its clients over loopback (port 0): TestClient on the client library's
// SimConnection, RawClient on a plain socket for the bytes a well-behaved client never sends. Reads time
// out after 10 s of wall time so that a broken server fails a test instead of hanging it.
#pragma once

#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <deque>
#include <limits>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <thread>

#include "../../support/loopback_tcp.hpp"
#include "api/api_server.hpp"
#include "objects/world_objects.hpp"
#include "physics/world.hpp"
#include "sim/runner.hpp"
#include "sim_api_client.hpp"

namespace uavsim::server::api::testing {

// A config whose clock starts held (tests step it explicitly).
inline ApiConfig paused() {
  ApiConfig c;
  c.start_paused = true;
  return c;
}

// The error code of a reply, "" for a success.
inline std::string error_code(const Json& reply) {
  return reply.value("ok", true) ? "" : reply["error"].value("code", "");
}

class TestServer {
 public:
  explicit TestServer(const std::string& world, ApiConfig config = {}, LinkControl* link = nullptr,
                      SeqWaiter* waiter = nullptr) {
    physics::ComposeOptions o;
    o.models_dir = UAVSIM_MODELS_DIR;
    sim_ = std::make_unique<sim::Simulation>(
        physics::World::load(std::string(UAVSIM_MODELS_DIR) + "/worlds/" + world, o), sim::SimConfig{});
    objects_ = objects::add_world_objects(*sim_);
    runner_ = std::make_unique<sim::Runner>(*sim_, 0.0);
    config.port = 0;
    api_ = std::make_unique<ApiServer>(*sim_, runner_.get(), objects_, config);
    api_->set_link_control(link);
    api_->set_seq_waiter(waiter);
    runner_->add_gate(sim::Phase::kQueuedTasks, "api", api_->gate());
    api_->start();
    loop_ = std::thread([this] { runner_->run_until(std::numeric_limits<double>::infinity()); });
  }
  ~TestServer() {
    runner_->stop();
    api_->shutdown();
    loop_.join();
  }
  uint16_t port() const { return api_->port(); }
  sim::Simulation& sim() { return *sim_; }  // only while the loop is held (paused)

 private:
  std::unique_ptr<sim::Simulation> sim_;
  objects::ObjectSet objects_;
  std::unique_ptr<sim::Runner> runner_;
  std::unique_ptr<ApiServer> api_;
  std::thread loop_;
};

// The sim API as launchers use it (SimConnection): each request's reply in its wire form ({"ok", "result"}
// or {"ok": false, "error": {"code", "message"}}; null if none came) and the streamed messages in order.
class TestClient {
 public:
  explicit TestClient(uint16_t port) : client_(port) {}
  const Json& hello() const { return client_.hello(); }
  // what the server streams comes on the shared-memory stream from now on (SimApiClient)
  bool use_shared_memory() { return client_.use_shared_memory(); }
  Json request(Json j) { return client_.request(std::move(j)); }
  // the next streamed message (null after a 10 s timeout)
  Json read_message() { return client_.read().json; }
  // the next streamed message of a given "event" kind, skipping others
  Json next_event(const std::string& kind) { return client_.next_event(kind).json; }

 private:
  SimApiClient client_;
};

// The raw wire: request lines as bytes, for malformed or pipelined input, half-closed sockets and the
// wire format itself (ids echoed, replies in order).
class RawClient {
 public:
  explicit RawClient(uint16_t port) {
    fd_ = socket(AF_INET, SOCK_STREAM, 0);
    EXPECT_TRUE(uavsim::testing::connect_loopback_tcp(fd_, port));
    hello_ = read_message();
  }
  ~RawClient() { close(fd_); }
  const Json& hello() const { return hello_; }

  void send_raw(const std::string& text) {
    size_t off = 0;
    while (off < text.size()) {
      const ssize_t n = ::send(fd_, text.data() + off, text.size() - off, MSG_NOSIGNAL);
      ASSERT_GT(n, 0);
      off += static_cast<size_t>(n);
    }
  }
  void send(const Json& j) { send_raw(j.dump() + "\n"); }
  // shuts down the sending side (the server sees EOF); 0 on success
  int shutdown_sending() { return ::shutdown(fd_, SHUT_WR); }
  // true once the server has closed the connection and everything it sent has been read
  bool at_eof() {
    for (;;) {
      pollfd p{fd_, POLLIN, 0};
      if (poll(&p, 1, 10000) <= 0) return false;
      char tmp[4096];
      const ssize_t n = recv(fd_, tmp, sizeof(tmp), 0);
      if (n <= 0) return n == 0;
      buf_.append(tmp, static_cast<size_t>(n));
    }
  }

  // the next message of any kind (null after a 10 s timeout)
  Json read_message() {
    if (!pending_.empty()) {
      Json j = pending_.front();
      pending_.pop_front();
      return j;
    }
    return read_wire();
  }
  // the next reply (a message with "ok"); async messages met on the way are kept for read_message
  Json reply() {
    std::deque<Json> skipped;
    for (;;) {
      Json j = pending_.empty() ? read_wire() : pop();
      if (j.is_null() || j.contains("ok")) {
        for (auto it = skipped.rbegin(); it != skipped.rend(); ++it) pending_.push_front(*it);
        return j;
      }
      skipped.push_back(j);
    }
  }
  Json request(Json j) {
    send(j);
    return reply();
  }
  // the next async message of a given "event" kind, skipping others
  Json next_event(const std::string& kind) {
    for (;;) {
      Json j = read_message();
      if (j.is_null() || (j.contains("event") && j["event"] == kind)) return j;
    }
  }

 private:
  Json pop() {
    Json j = pending_.front();
    pending_.pop_front();
    return j;
  }
  Json read_wire() {
    for (;;) {
      const size_t nl = buf_.find('\n');
      if (nl != std::string::npos) {
        Json j = Json::parse(buf_.substr(0, nl), nullptr, false);
        buf_.erase(0, nl + 1);
        return j;
      }
      pollfd p{fd_, POLLIN, 0};
      if (poll(&p, 1, 10000) <= 0) return nullptr;
      char tmp[65536];
      const ssize_t n = recv(fd_, tmp, sizeof(tmp), 0);
      if (n <= 0) return nullptr;
      buf_.append(tmp, static_cast<size_t>(n));
    }
  }
  int fd_ = -1;
  std::string buf_;
  std::deque<Json> pending_;
  Json hello_;
};

}  // namespace uavsim::server::api::testing
