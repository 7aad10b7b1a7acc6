// SPDX-License-Identifier: Apache-2.0 OR GPL-2.0-only
// Copyright the uavsim authors.
//
// The lockstep protocol between uavsim-server (Apache-2.0) and uavsim-ns3-radio (GPL-2.0-only):
// plain C++ and the standard library only, offered under either license so both programs can use
// it without one linking the other (ns3/README.md).
//
// Over a stream socket pair, one message at a time, each a u32 body length then the body; the body
// starts with a u8 MessageType. Values are in the host's byte order (both ends are on one machine,
// the helper is spawned by the server). Every request gets exactly one reply:
//   kInit   u32 vehicles, u64 seed, Channel          -> kReady u32 max_payload_bytes
//   kConfig Channel                                  -> kReady
//   kReset  u64 seed                                 -> kReady
//   kStep   u32 slices, slices x Slice, i64 ahead_ns     -> kStepDone (below)
//     Slice i64 t_ns, u8 with_kinematics, [vehicles x (3 f64 position_enu_m, 3 f64
//           velocity_enu_m_s)],
//           u32 n, n x (u32 from, u32 to, f64 extra_loss_db),
//           u32 n, n x (u32 from, i32 to, u64 seq, i64 queued_ns, i64 at_ns, u16 bytes, bytes)
//   kQuit                                            -> (none; the helper exits 0)
//   kStepDone  i64 now_ns, u8 busy, i64 quiet_until_ns,
//           u32 n, n x Delivery (u32 to, u32 from, u64 seq, u8 broadcast, i64 queued_ns,
//                                i64 tx_start_ns, i64 rx_ns, u8 lqi, u16 bytes, bytes),
//           u32 n, n x (u32 from, u64 seq, u8 status: ConfirmStatus),
//           u32 n, n x (u32 from, u32 to, u8 Counter)   (to = from for a vehicle's own counters)
//   kError  u16 bytes, text (a request the helper could not carry out; the server ends the run)
// Each Slice of a kStep runs ns-3 to its t_ns (Simulator::Stop(t - Now()) + Run()), then sets the
// positions, the extra losses and hands the frames to the MACs in the order given (at_ns -1: at
// once; else at at_ns, a TDMA slot's start or a frame's spread entry, within the next step).
// busy: frames in flight after the slices; quiet_until_ns: they report nothing before that time,
// so the server steps the helper again at the first step at or after it (or when it hands
// frames). Then, if busy and ahead_ns >= quiet_until_ns (-1: never), the helper runs on to
// ahead_ns, where the server's next step will be, while the server computes that step: the run
// the server's next kStep would have started with, so nothing it reports changes, only when. The
// kStepDone reports what happened since the previous one (receptions up to now_ns, the helper's
// clock after any run ahead) with busy and quiet_until_ns as they were after the slices.
#pragma once

#include <poll.h>
#include <sys/socket.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

namespace uavsim::ns3wire {

enum class MessageType : uint8_t {
  kInit = 1,
  kConfig = 2,
  kReset = 3,
  kStep = 4,
  kQuit = 5,
  kReady = 101,
  kStepDone = 102,
  kError = 103,
};

enum class ConfirmStatus : uint8_t {
  kSuccess = 0,
  kChannelAccessFailure = 1,
  kNoAck = 2,
  kOther = 3
};

// what the counter events count (radio_model.hpp LinkStats, per link; kTransmitted and
// kChannelAccessFailure are the sender's own, with to = from)
enum class Counter : uint8_t {
  kSent = 0,
  kDelivered = 1,
  kLost = 2,
  kOutOfRange = 3,
  kNoAck = 4,
  kTransmitted = 5,
  kChannelAccessFailure = 6,
};

// The channel's settings (the subset of the server's RadioConfig the helper models).
struct Channel {
  uint8_t log_distance = 0;  // 0: range (RangePropagationLossModel), 1: log-distance + shadowing
  double range_m = 100.0;
  double tx_power_dbm = 0.0;
  double sensitivity_dbm = -85.0;
  double reference_loss_db = 40.05;
  double path_loss_exponent = 2.5;
  double shadowing_sigma_db = 0.0;
  uint8_t tdma = 0;        // 1: frames come at their slots' starts; CSMA-CA without random backoff
  uint8_t technology = 0;  // 0: IEEE 802.15.4 (lr-wpan); 1: IEEE 802.11g ad hoc, 6 Mbit/s
};

inline constexpr uint32_t kMaxMessageBytes = 64u << 20;  // far above any step's traffic
inline constexpr uint32_t kMaxVehicles = 100000;
// the largest frame of any technology: 802.11's (an Ethernet MTU); 802.15.4 carries at most 127
inline constexpr uint16_t kMaxFrameBytes = 1500;

class Writer {
 public:
  template <typename T>
  void put(T v) {
    const size_t at = body_.size();
    body_.resize(at + sizeof(T));
    std::memcpy(body_.data() + at, &v, sizeof(T));
  }
  void bytes(const uint8_t* p, size_t n) { body_.insert(body_.end(), p, p + n); }
  void append(const Writer& other) { bytes(other.body_.data(), other.body_.size()); }
  const std::vector<uint8_t>& body() const { return body_; }
  // the message: length prefix and body
  std::vector<uint8_t> message() const {
    std::vector<uint8_t> m(4 + body_.size());
    const auto n = static_cast<uint32_t>(body_.size());
    std::memcpy(m.data(), &n, 4);
    if (!body_.empty()) std::memcpy(m.data() + 4, body_.data(), body_.size());
    return m;
  }

 private:
  std::vector<uint8_t> body_;
};

// Reads a body; every get checks the bounds (a short or malformed message sets !ok(), never reads
// past the end).
class Reader {
 public:
  Reader(const uint8_t* p, size_t n) : p_(p), n_(n) {}
  template <typename T>
  T get() {
    T v{};
    if (at_ + sizeof(T) > n_) {
      ok_ = false;
      return v;
    }
    std::memcpy(&v, p_ + at_, sizeof(T));
    at_ += sizeof(T);
    return v;
  }
  bool bytes(size_t n, std::vector<uint8_t>* out) {
    if (at_ + n > n_) {
      ok_ = false;
      return false;
    }
    out->assign(p_ + at_, p_ + at_ + n);
    at_ += n;
    return true;
  }
  bool ok() const { return ok_; }
  size_t left() const { return n_ - at_; }

 private:
  const uint8_t* p_;
  size_t n_;
  size_t at_ = 0;
  bool ok_ = true;
};

inline void put_channel(Writer& w, const Channel& c) {
  w.put<uint8_t>(c.log_distance);
  w.put(c.range_m);
  w.put(c.tx_power_dbm);
  w.put(c.sensitivity_dbm);
  w.put(c.reference_loss_db);
  w.put(c.path_loss_exponent);
  w.put(c.shadowing_sigma_db);
  w.put<uint8_t>(c.tdma);
  w.put<uint8_t>(c.technology);
}

inline Channel get_channel(Reader& r) {
  Channel c;
  c.log_distance = r.get<uint8_t>();
  c.range_m = r.get<double>();
  c.tx_power_dbm = r.get<double>();
  c.sensitivity_dbm = r.get<double>();
  c.reference_loss_db = r.get<double>();
  c.path_loss_exponent = r.get<double>();
  c.shadowing_sigma_db = r.get<double>();
  c.tdma = r.get<uint8_t>();
  c.technology = r.get<uint8_t>();
  return c;
}

enum class IoResult { kOk, kClosed, kTimeout, kError, kTooLarge };

inline const char* io_result_name(IoResult r) {
  switch (r) {
    case IoResult::kOk:
      return "ok";
    case IoResult::kClosed:
      return "the other end closed the connection";
    case IoResult::kTimeout:
      return "no answer in time";
    case IoResult::kError:
      return "socket error";
    case IoResult::kTooLarge:
      return "message too large";
  }
  return "?";
}

// Writes a whole message (MSG_NOSIGNAL: a dead peer is kClosed, not SIGPIPE).
inline IoResult write_all(int fd, const std::vector<uint8_t>& m) {
  size_t at = 0;
  while (at < m.size()) {
    const ssize_t n = ::send(fd, m.data() + at, m.size() - at, MSG_NOSIGNAL);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) return errno == EPIPE || errno == ECONNRESET ? IoResult::kClosed : IoResult::kError;
    at += static_cast<size_t>(n);
  }
  return IoResult::kOk;
}

// Reads one message's body within timeout_ms of wall time (< 0: no limit).
inline IoResult read_message(int fd, int timeout_ms, std::vector<uint8_t>* body) {
  using Clock = std::chrono::steady_clock;
  const auto deadline = Clock::now() + std::chrono::milliseconds(timeout_ms < 0 ? 0 : timeout_ms);
  auto read_exact = [&](uint8_t* p, size_t n) {
    size_t at = 0;
    while (at < n) {
      if (timeout_ms >= 0) {
        const auto left =
            std::chrono::duration_cast<std::chrono::milliseconds>(deadline - Clock::now());
        pollfd pfd{fd, POLLIN, 0};
        const int ready = ::poll(&pfd, 1, static_cast<int>(std::max<int64_t>(0, left.count())));
        if (ready < 0 && errno == EINTR) continue;
        if (ready < 0) return IoResult::kError;
        if (ready == 0) return IoResult::kTimeout;
      }
      const ssize_t got = ::recv(fd, p + at, n - at, 0);
      if (got < 0 && errno == EINTR) continue;
      if (got < 0) return errno == ECONNRESET ? IoResult::kClosed : IoResult::kError;
      if (got == 0) return IoResult::kClosed;
      at += static_cast<size_t>(got);
    }
    return IoResult::kOk;
  };
  uint32_t n = 0;
  IoResult r = read_exact(reinterpret_cast<uint8_t*>(&n), 4);
  if (r != IoResult::kOk) return r;
  if (n > kMaxMessageBytes) return IoResult::kTooLarge;
  body->resize(n);
  return n == 0 ? IoResult::kOk : read_exact(body->data(), n);
}

}  // namespace uavsim::ns3wire
