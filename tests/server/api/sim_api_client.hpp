// The sim API client of the server's system tests: the client library's SimConnection (as launchers
// use it), with the reply of each request in its wire form and the streamed messages kept in
// arrival order. Waits end after a fixed wall time (null) so that a broken server fails a test
// instead of hanging it.
#pragma once

#include <gtest/gtest.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <deque>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <utility>
#include <vector>

#include "../../support/loopback_tcp.hpp"
#include "uavsim/client/sim_connection.hpp"

namespace uavsim::server::api::testing {

using Json = nlohmann::json;

// A streamed message: its JSON, and for a frame its image bytes.
struct Message {
  Json json;
  std::string bytes;
};

// A request's reply as the wire carries it: {"ok": true, "result": ...}, or {"ok": false, "error":
// {"code", "message"}} read back from SimConnection's failure message "OP: CODE: message"; null
// when no reply came (a timeout, a lost connection).
inline Json wire_reply(const std::string& op, const client::Result<Json>& r) {
  if (r) return Json{{"ok", true}, {"result", *r}};
  const std::string prefix = op + ": ";
  const std::string& m = r.message();
  if (m.rfind(prefix, 0) != 0) return nullptr;  // a local failure ("sim API: ..."): no reply
  const size_t end = m.find(": ", prefix.size());
  const std::string code =
      m.substr(prefix.size(), end == std::string::npos ? std::string::npos : end - prefix.size());
  const std::string message = end == std::string::npos ? "" : m.substr(end + 2);
  return Json{{"ok", false}, {"error", {{"code", code}, {"message", message}}}};
}

class SimApiClient {
 public:
  // Connects over loopback; rcvbuf > 0 sets the socket's receive buffer first (a client that reads
  // slowly fills it sooner). wait_s: how long a request or a read waits.
  explicit SimApiClient(uint16_t port, int rcvbuf = 0, double wait_s = 10.0) : wait_s_(wait_s) {
    const int fd = socket(AF_INET, SOCK_STREAM, 0);
    if (rcvbuf > 0) setsockopt(fd, SOL_SOCKET, SO_RCVBUF, &rcvbuf, sizeof(rcvbuf));
    EXPECT_TRUE(uavsim::testing::connect_loopback_tcp(fd, port));
    auto c = client::SimConnection::adopt(fd, wait_s_);
    EXPECT_TRUE(c) << c.message();
    if (c) conn_ = std::move(*c);
  }

  // Moves what the server streams to this client onto the shared-memory stream (false, with a test
  // failure, if it cannot).
  bool use_shared_memory() {
    if (!conn_) return false;
    const auto r = conn_->use_shared_memory(wait_s_);
    EXPECT_TRUE(r) << r.message();
    return static_cast<bool>(r);
  }

  // The server's hello (null if the connection failed).
  const Json& hello() const { return conn_ ? conn_->hello() : null_; }

  // Sends a request and returns its reply (wire_reply); streamed messages read meanwhile stay
  // queued, in arrival order, for read().
  Json request(Json j) {
    if (!conn_) return nullptr;
    const std::string op = j.value("op", "");
    return wire_reply(op, conn_->request(std::move(j), wait_s_));
  }

  // The next streamed message, in arrival order (null json after the wait).
  Message read() {
    const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(wait_s_);
    while (unread_.empty() && conn_ && conn_->connected()) {
      for (client::SimMessage& m : conn_->take_messages())
        unread_.push_back({std::move(m.json), std::move(m.payload)});
      if (!unread_.empty()) break;
      const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
          end - std::chrono::steady_clock::now());
      if (left.count() <= 0 ||
          !conn_->poll(static_cast<int>(std::min<int64_t>(left.count(), 1000))))
        break;
    }
    if (unread_.empty()) return {};
    Message m = std::move(unread_.front());
    unread_.pop_front();
    return m;
  }
  // The next streamed message of an event kind (null json after the wait); the others before it
  // are appended to *before, or dropped when before is null.
  Message next_event(const std::string& kind, std::vector<Message>* before = nullptr) {
    for (;;) {
      Message m = read();
      if (m.json.is_null() || m.json.value("event", "") == kind) return m;
      if (before) before->push_back(std::move(m));
    }
  }

 private:
  double wait_s_;
  std::unique_ptr<client::SimConnection> conn_;
  std::deque<Message> unread_;  // taken from the connection's queue, not returned yet
  Json null_;
};

}  // namespace uavsim::server::api::testing
