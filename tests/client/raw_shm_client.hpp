// RawShmClient: a sim API client that speaks the wire itself (tests of the shared-memory stream,
// docs/protocol.md "Shared-memory stream"): request lines on TCP until it takes the stream, then
// its input from the ring it maps, and, when the offer gave one, its requests through the request
// ring, as lines or binary records (common/shm_requests.hpp). It keeps a mapping of its own, to
// break the rings with.
#pragma once

#include <fcntl.h>
#include <gtest/gtest.h>
#include <poll.h>
#include <sys/mman.h>
#include <unistd.h>

#include <memory>
#include <nlohmann/json.hpp>
#include <span>
#include <string>
#include <vector>

#include "net.hpp"
#include "shm_stream.hpp"
#include "uavsim/common/shm_ring.hpp"

namespace uavsim::client::testing {

using Json = nlohmann::json;

// A client that speaks the wire itself: request lines on TCP, its input from the ring it maps.
class RawShmClient {
 public:
  explicit RawShmClient(int port) {
    auto fd = net::tcp_connect("127.0.0.1", port, 10.0);
    EXPECT_TRUE(fd) << fd.message();
    if (!fd) return;
    fd_ = *fd;
    std::string buf;
    EXPECT_TRUE(net::read_line(fd_, buf, 10.0));  // the hello
    EXPECT_TRUE(buf.empty());
  }
  ~RawShmClient() {
    if (region_ != nullptr) munmap(region_, size_);
    if (fd_ >= 0) close(fd_);
  }
  // a request and its reply on TCP (before the stream is taken)
  Json tcp_request(const Json& request) {
    if (!net::send_all(fd_, request.dump() + "\n", 10.0)) return Json();
    auto line = net::read_line(fd_, tcp_buf_, 10.0);
    return line ? Json::parse(*line, nullptr, false) : Json();
  }
  // takes the offered stream: a mapping of its own (to break it with) and the reader
  bool take_stream(const Json& offer) {
    const std::string name = common::shm::object_name(offer.value("token", std::string()));
    size_ = common::shm::region_bytes(offer.value("ring_bytes", std::size_t{0}));
    ring_size_ = size_;
    if (offer.contains("request_ring_bytes"))
      size_ += common::shm::region_bytes(offer.value("request_ring_bytes", std::size_t{0}));
    const int fd = shm_open(name.c_str(), O_RDWR, 0);
    if (fd < 0 || size_ == 0) return false;
    region_ = mmap(nullptr, size_, PROT_READ | PROT_WRITE, MAP_SHARED, fd, 0);
    close(fd);
    auto s = ShmStream::open(offer);
    EXPECT_TRUE(s) << s.message();
    if (!s || region_ == MAP_FAILED) return false;
    stream_ = std::move(*s);
    return true;
  }
  void send(const Json& request) { EXPECT_TRUE(net::send_all(fd_, request.dump() + "\n", 10.0)); }
  // through the request ring: a request as its line, or a binary record; deferred, the server is
  // woken for it only by flush() (a burst: a lockstep client's tick of requests and its done)
  void send_on_ring(const Json& request, bool deferred = false) {
    const std::string line = request.dump() + "\n";
    send_record(common::shm::RecordType::kStream,
                {reinterpret_cast<const std::uint8_t*>(line.data()), line.size()}, deferred);
  }
  void send_record(common::shm::RecordType type, std::span<const std::uint8_t> payload,
                   bool deferred = false) {
    std::string why;
    EXPECT_TRUE(stream_->write_request(type, payload, 10.0, &why, deferred)) << why;
  }
  void flush() { stream_->flush_wakeup(); }
  bool has_request_ring() const { return stream_ && stream_->has_requests(); }
  // the next record of the ring (waits on its wake-up, 10 s); false when the stream ended or broke
  bool next(common::shm::RingReader::Record* rec) {
    for (int waits = 0; waits < 2; ++waits) {
      stream_->drain_wakeups();
      std::string why;
      const auto status = stream_->next(rec, &why);
      if (status == common::shm::RingReader::Status::kRecord) return true;
      if (status == common::shm::RingReader::Status::kCorrupt) return false;
      pollfd p{stream_->wake_fd(), POLLIN, 0};
      if (poll(&p, 1, 10000) <= 0) return false;
    }
    return false;
  }
  // the ring's wake-up hangs up: the server has let go of the stream (the connection is closed)
  bool hung_up() {
    pollfd p{stream_->wake_fd(), POLLIN, 0};
    for (int i = 0; i < 100 && poll(&p, 1, 100) >= 0; ++i) {
      if (p.revents & POLLHUP) return true;
      stream_->drain_wakeups();
    }
    return false;
  }
  common::shm::RingHeader* header() { return static_cast<common::shm::RingHeader*>(region_); }
  common::shm::RingHeader* request_header() {
    return reinterpret_cast<common::shm::RingHeader*>(static_cast<std::uint8_t*>(region_) +
                                                      ring_size_);
  }
  // Sleeps as a lockstep client does, until its next wake-up (10 s at most); then, as woken:
  // "woken N" (the wake-up bytes that were in the FIFO) and every record there, a reply as "ID ok"
  // or "ID ERROR_CODE", a tick as "tick N". Empty when nothing woke it.
  std::vector<std::string> sleep_until_woken() {
    std::vector<std::string> out;
    pollfd p{stream_->wake_fd(), POLLIN, 0};
    if (poll(&p, 1, 10000) <= 0) return out;
    int wakes = 0;
    char buf[64];
    for (ssize_t n; (n = read(stream_->wake_fd(), buf, sizeof(buf))) > 0;)
      wakes += static_cast<int>(n);
    out.push_back("woken " + std::to_string(wakes));
    stream_->drain_wakeups();  // nothing left to drain: arms it for the next sleep
    common::shm::RingReader::Record rec;
    std::string why;
    while (stream_->next(&rec, &why) == common::shm::RingReader::Status::kRecord) {
      if (rec.type == common::shm::RecordType::kTick) {
        const auto tick = common::shm::decode_tick(rec.payload, &why);
        out.push_back(tick ? "tick " + std::to_string(tick->tick) : why);
        continue;
      }
      const Json j =
          Json::parse(std::string(rec.payload.begin(), rec.payload.end()), nullptr, false);
      const std::string id = j.value("id", Json()).is_string() ? j["id"].get<std::string>()
                                                               : j.value("id", Json()).dump();
      out.push_back(id + " " + (j.value("ok", false) ? "ok" : j["error"].value("code", "?")));
    }
    return out;
  }
  // several requests in one write (one burst, as a lockstep client sends its tick's work)
  void send_burst(const std::vector<Json>& requests) {
    std::string lines;
    for (const Json& r : requests) lines += r.dump() + "\n";
    EXPECT_TRUE(net::send_all(fd_, lines, 10.0));
  }

 private:
  int fd_ = -1;
  std::string tcp_buf_;
  void* region_ = nullptr;
  std::size_t size_ = 0;
  std::size_t ring_size_ = 0;  // the server's ring's part of the region
  std::unique_ptr<ShmStream> stream_;
};

}  // namespace uavsim::client::testing
