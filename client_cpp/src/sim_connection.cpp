#include "uavsim/client/sim_connection.hpp"

#include <fcntl.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cassert>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstring>
#include <deque>
#include <thread>
#include <utility>

#include "api_stream.hpp"
#include "net.hpp"
#include "shm_stream.hpp"
#include "uavsim/common/api_error.hpp"
#include "uavsim/common/base64.hpp"

namespace uavsim::client {

namespace {

using Json = nlohmann::json;
using SteadyClock = std::chrono::steady_clock;

constexpr std::size_t kReadChunk = 1u << 16;

SteadyClock::time_point deadline_after(double timeout_s) {
  // a NaN or negative timeout is no wait; a huge one is a day (no overflow of the time point)
  const double s = std::isfinite(timeout_s) ? std::clamp(timeout_s, 0.0, 86400.0)
                                            : (timeout_s > 0 ? 86400.0 : 0.0);
  return SteadyClock::now() +
         std::chrono::duration_cast<SteadyClock::duration>(std::chrono::duration<double>(s));
}

int ms_until(SteadyClock::time_point end) {
  const auto left =
      std::chrono::duration_cast<std::chrono::milliseconds>(end - SteadyClock::now()).count();
  return static_cast<int>(std::clamp<int64_t>(left, 0, 1000 * 86400));
}

}  // namespace

std::string SimMessage::kind() const {
  if (!json.is_object()) return "";
  const auto it = json.find("event");
  return it != json.end() && it->is_string() ? it->get<std::string>() : "";
}

Error sim_api_error(std::string_view code) {
  const std::optional<common::ApiError> e = common::api_error_from_code(code);
  if (!e) return Error::kFailed;  // a code of a newer server
  switch (*e) {
    case common::ApiError::kBadJson:
    case common::ApiError::kBadRequest:
    case common::ApiError::kLineTooLong:
    case common::ApiError::kMissingField:
    case common::ApiError::kBadField:
    case common::ApiError::kUnknownVehicle:
    case common::ApiError::kFrameTooLarge:
    case common::ApiError::kBadBase64:
      return Error::kInvalidArgument;
    case common::ApiError::kUnknownOp:
    case common::ApiError::kNotAvailable:
      return Error::kUnsupported;
    case common::ApiError::kNotJoined:
    case common::ApiError::kBadState:
      return Error::kNotReady;
    case common::ApiError::kBusy:
    case common::ApiError::kQueueFull:
    case common::ApiError::kOverloaded:
      return Error::kTemporarilyRejected;
    case common::ApiError::kUnauthorized:
    case common::ApiError::kForbidden:
      return Error::kDenied;
    case common::ApiError::kInterrupted:
    case common::ApiError::kIoError:
      return Error::kFailed;
  }
  return Error::kFailed;
}

struct SimConnection::Impl {
  int fd = -1;
  std::thread::id owner = std::this_thread::get_id();
  Json hello;
  int64_t next_id = 0;
  ApiStream stream;              // bytes read, cut into whole messages
  std::deque<SimMessage> queue;  // streamed messages for take_messages()
  std::map<std::string, std::function<void(const SimMessage&)>> handlers;
  std::deque<Json> replies;       // replies read, not yet claimed by request()
  std::optional<Failure> broken;  // why the connection is closed
  // the shared-memory stream (use_shared_memory): everything the server sends comes from it
  std::unique_ptr<ShmStream> ring;
  common::shm::RingReader::Record record;  // reused: its buffer keeps its capacity

  ~Impl() { close_fd(); }

  void assert_owner_thread() const { assert(owner == std::this_thread::get_id()); }

  void close_fd() {
    if (fd >= 0) ::close(fd);
    fd = -1;
    ring.reset();
  }
  Failure fail(Error code, std::string message) {
    close_fd();
    if (!broken) broken = Failure{code, std::move(message)};
    return *broken;
  }

  // a whole message: a reply (has "ok") is kept for request(); a streamed one is dispatched
  void deliver(Json j, std::string payload) {
    if (!j.contains("event") && j.contains("ok")) {
      replies.push_back(std::move(j));
      return;
    }
    SimMessage m{std::move(j), std::move(payload)};
    const auto h = handlers.find(m.kind());
    if (h != handlers.end() && h->second) {
      h->second(m);
    } else {
      queue.push_back(std::move(m));
    }
  }

  // bytes => whole messages delivered; a failure when the stream is malformed (api_stream.hpp's
  // limits, or a line that is not a JSON object)
  std::optional<Failure> parse(const char* data, std::size_t size) {
    stream.feed(data, size, [this](const Json& j, std::string_view payload) {
      if (!j.is_object()) {
        stream.stop("a line that is not a JSON object");
        return;
      }
      deliver(j, std::string(payload));
    });
    if (stream.error()) return fail(Error::kProtocol, *stream.error());
    return std::nullopt;
  }

  // a tick record of the shared-memory stream as the socket would carry it to this connection: the
  // radio frames that arrived since the last tick (there are some only for a batch subscription)
  // as one radio_batch line, then the tick
  std::optional<Failure> deliver_tick(const std::vector<std::uint8_t>& payload) {
    std::string why;
    auto tick = common::shm::decode_tick(payload, &why);
    if (!tick) return fail(Error::kProtocol, "sim API: shared-memory stream: " + why);
    if (!tick->frames.empty()) {
      Json frames = Json::array();
      for (const auto& f : tick->frames) {
        frames.push_back(Json::array({f.to, f.from, f.seq, f.broadcast, f.time_s, f.sent_time_s,
                                      common::base64_encode(f.data)}));
      }
      deliver({{"event", "radio_batch"}, {"time", tick->time_s}, {"frames", std::move(frames)}},
              {});
    }
    deliver({{"event", "tick"}, {"tick", tick->tick}, {"time", tick->time_s}}, {});
    return std::nullopt;
  }

  // every record waiting in the ring, delivered
  std::optional<Failure> read_ring() {
    const bool closed = ring->drain_wakeups();  // and armed: a record written from now wakes us
    std::string why;
    for (;;) {
      const auto status = ring->next(&record, &why);
      if (status == common::shm::RingReader::Status::kEmpty) break;
      if (status == common::shm::RingReader::Status::kCorrupt)
        return fail(Error::kProtocol, "sim API: shared-memory stream: " + why);
      if (record.type != common::shm::RecordType::kStream &&
          record.type != common::shm::RecordType::kTick) {
        return fail(Error::kProtocol, "sim API: shared-memory stream: a request record");
      }
      if (record.type == common::shm::RecordType::kStream) {
        if (auto e =
                parse(reinterpret_cast<const char*>(record.payload.data()), record.payload.size()))
          return e;
      } else if (auto e = deliver_tick(record.payload)) {
        return e;
      }
      if (!ring) return broken;  // a handler's message broke the connection
    }
    if (closed) return fail(Error::kConnectionLost, "sim API: the server closed the connection");
    return std::nullopt;
  }

  // waits up to timeout_ms for bytes, then reads all there are and delivers the whole messages
  std::optional<Failure> read_some(int timeout_ms) {
    if (fd < 0) return broken ? *broken : Failure{Error::kNotConnected, "sim API: not connected"};
    if (ring) {
      // records may wait without a wake-up of their own (read before the last one was armed)
      const std::size_t before = replies.size() + queue.size();
      if (auto e = read_ring()) return e;
      if (replies.size() + queue.size() > before || timeout_ms == 0) return std::nullopt;
      pollfd w{ring->wake_fd(), POLLIN, 0};
      if (::poll(&w, 1, timeout_ms) < 0 && errno != EINTR)
        return fail(Error::kIo, std::string("sim API: poll: ") + std::strerror(errno));
      return read_ring();
    }
    pollfd p{fd, POLLIN, 0};
    const int r = ::poll(&p, 1, timeout_ms);
    if (r < 0) {
      if (errno == EINTR) return std::nullopt;
      return fail(Error::kIo, std::string("sim API: poll: ") + std::strerror(errno));
    }
    if (r == 0) return std::nullopt;
    char tmp[kReadChunk];
    for (;;) {
      const ssize_t n = ::recv(fd, tmp, sizeof(tmp), MSG_DONTWAIT);
      if (n > 0) {
        if (auto e = parse(tmp, static_cast<std::size_t>(n))) return e;
        if (static_cast<std::size_t>(n) < sizeof(tmp)) break;
        continue;
      }
      if (n == 0) return fail(Error::kConnectionLost, "sim API: the server closed the connection");
      if (errno == EINTR) continue;
      if (errno == EAGAIN || errno == EWOULDBLOCK) break;
      return fail(Error::kConnectionLost, std::string("sim API: recv: ") + std::strerror(errno));
    }
    return std::nullopt;
  }

  bool send_line(const std::string& line, SteadyClock::time_point end) {
    if (ring && ring->has_requests()) {
      // the request ring: the server's I/O thread reads it without waiting for us
      std::string why;
      const auto* bytes = reinterpret_cast<const std::uint8_t*>(line.data());
      const double left_s = std::chrono::duration<double>(end - SteadyClock::now()).count();
      return ring->write_request(common::shm::RecordType::kStream, {bytes, line.size()}, left_s,
                                 &why);
    }
    std::size_t sent = 0;
    while (sent < line.size()) {
      const ssize_t n =
          ::send(fd, line.data() + sent, line.size() - sent, MSG_NOSIGNAL | MSG_DONTWAIT);
      if (n > 0) {
        sent += static_cast<std::size_t>(n);
        continue;
      }
      if (n < 0 && errno == EINTR) continue;
      if (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK)) {
        // the server reads only while we read its replies: keep reading while waiting to send
        pollfd p{fd, POLLOUT | POLLIN, 0};
        if (::poll(&p, 1, ms_until(end)) <= 0) return false;
        if ((p.revents & POLLIN) != 0 && read_some(0)) return false;
        if (fd < 0) return false;
        continue;
      }
      return false;
    }
    return true;
  }

  // Waits until end for the reply to request id (op names it in messages), dropping the replies
  // before it (of requests that timed out); its result, or the server's error as a Failure.
  Result<Json> await_reply(int64_t id, const std::string& op, SteadyClock::time_point end);
};

SimConnection::SimConnection(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
SimConnection::~SimConnection() = default;

Result<std::unique_ptr<SimConnection>> SimConnection::connect(const std::string& host,
                                                              uint16_t port, double timeout_s) {
  const auto end = deadline_after(timeout_s);
  auto fd = net::tcp_connect(host, port, timeout_s);
  if (!fd) return fd.error();
  return adopt(*fd, std::max(0.0, std::chrono::duration<double>(end - SteadyClock::now()).count()));
}

Result<std::unique_ptr<SimConnection>> SimConnection::adopt(int fd, double timeout_s) {
  auto impl = std::make_unique<Impl>();
  impl->fd = fd;
  if (fd < 0) return Failure{Error::kInvalidArgument, "sim API: no socket"};
  // hello: the first message; a connection past the server's limit gets `overloaded` instead
  const auto end = deadline_after(timeout_s);
  while (impl->replies.empty() && impl->queue.empty()) {
    if (SteadyClock::now() >= end) {
      return Failure{Error::kTimeout, "sim API: no hello from the server"};
    }
    if (auto e = impl->read_some(ms_until(end))) return *e;
  }
  if (!impl->replies.empty()) {
    const Json& r = impl->replies.front();
    const Json err = r.value("error", Json::object());
    return Failure{Error::kProtocol,
                   "sim API refused the connection: " +
                       (err.is_object() ? err.value("code", std::string("?")) + ": " +
                                              err.value("message", std::string())
                                        : r.dump())};
  }
  SimMessage first = std::move(impl->queue.front());
  impl->queue.pop_front();
  if (first.json.value("hello", std::string()) != "uavsim") {
    return Failure{Error::kProtocol, "sim API: the peer did not greet as a uavsim server"};
  }
  impl->hello = std::move(first.json);
  return std::unique_ptr<SimConnection>(new SimConnection(std::move(impl)));
}

const nlohmann::json& SimConnection::hello() const {
  impl_->assert_owner_thread();
  return impl_->hello;
}
bool SimConnection::connected() const {
  impl_->assert_owner_thread();
  return impl_->fd >= 0;
}
int SimConnection::fd() const {
  impl_->assert_owner_thread();
  if (impl_->ring) return impl_->ring->wake_fd();
  return impl_->fd;
}

namespace {

// The op's name for messages (a non-string op as its JSON).
std::string op_name(const Json& req) {
  return req["op"].is_string() ? req["op"].get<std::string>() : req["op"].dump();
}

}  // namespace

Result<nlohmann::json> SimConnection::Impl::await_reply(int64_t id, const std::string& op,
                                                        SteadyClock::time_point end) {
  for (;;) {
    // replies come in request order: older ones (of requests that timed out) are dropped
    while (!replies.empty()) {
      Json r = std::move(replies.front());
      replies.pop_front();
      const auto rid = r.find("id");
      if (rid != r.end() && rid->is_number_integer() && rid->get<int64_t>() == id) {
        if (r.value("ok", false) == true) {
          const auto res = r.find("result");
          return res != r.end() ? *res : Json::object();
        }
        const Json err = r.value("error", Json::object());
        const std::string code =
            err.is_object() ? err.value("code", std::string("failed")) : std::string("failed");
        const std::string msg = err.is_object() ? err.value("message", std::string()) : r.dump();
        return Failure{sim_api_error(code), op + ": " + code + ": " + msg};
      }
      if (rid != r.end() && rid->is_null() && r.value("ok", true) == false) {
        // an error not tied to a request: `overloaded` ends the connection
        const Json err = r.value("error", Json::object());
        if (err.is_object() && err.value("code", std::string()) == "overloaded") {
          return fail(Error::kConnectionLost,
                      "sim API: overloaded: " + err.value("message", std::string()));
        }
      }
    }
    if (SteadyClock::now() >= end) {
      return Failure{Error::kTimeout, "sim API: no reply to " + op + " in time"};
    }
    if (auto e = read_some(ms_until(end))) return *e;
  }
}

Result<nlohmann::json> SimConnection::request(nlohmann::json req, double timeout_s) {
  std::vector<Result<Json>> one = request_all({std::move(req)}, timeout_s);
  return std::move(one.front());
}

std::vector<Result<nlohmann::json>> SimConnection::request_all(std::vector<nlohmann::json> reqs,
                                                               double timeout_s) {
  Impl& m = *impl_;
  m.assert_owner_thread();
  if (reqs.empty()) return {};
  const auto all_fail = [&](const Failure& f) { return std::vector<Result<Json>>(reqs.size(), f); };
  for (const Json& req : reqs) {
    if (!req.is_object() || !req.contains("op")) {
      return all_fail(
          Failure{Error::kInvalidArgument, "sim API: a request is an object with an \"op\""});
    }
  }
  if (m.fd < 0) {
    return all_fail(m.broken ? *m.broken : Failure{Error::kNotConnected, "sim API: not connected"});
  }
  // every line in one write: the server wakes once for all of them and answers them in order
  std::string lines;
  const int64_t first_id = m.next_id + 1;
  for (Json& req : reqs) {
    req["id"] = ++m.next_id;
    lines += req.dump();
    lines += '\n';
  }
  const auto end = deadline_after(timeout_s);
  if (!m.send_line(lines, end)) {
    if (m.broken) return all_fail(*m.broken);
    return all_fail(
        m.fail(Error::kConnectionLost, "sim API: cannot send " + op_name(reqs.front())));
  }
  std::vector<Result<Json>> results;
  results.reserve(reqs.size());
  for (size_t i = 0; i < reqs.size(); ++i) {
    results.push_back(m.await_reply(first_id + static_cast<int64_t>(i), op_name(reqs[i]), end));
  }
  return results;
}

void SimConnection::on_message(const std::string& kind,
                               std::function<void(const SimMessage&)> handler) {
  impl_->assert_owner_thread();
  if (handler) {
    impl_->handlers[kind] = std::move(handler);
  } else {
    impl_->handlers.erase(kind);
  }
}

std::vector<SimMessage> SimConnection::take_messages() {
  impl_->assert_owner_thread();
  std::vector<SimMessage> out(std::make_move_iterator(impl_->queue.begin()),
                              std::make_move_iterator(impl_->queue.end()));
  impl_->queue.clear();
  return out;
}

Result<void> SimConnection::poll(int timeout_ms) {
  impl_->assert_owner_thread();
  if (auto e = impl_->read_some(std::max(0, timeout_ms))) return *e;
  // replies nobody waits for (of requests that timed out) are dropped
  impl_->replies.clear();
  return ok();
}

Result<void> SimConnection::use_shared_memory(double timeout_s) {
  Impl& m = *impl_;
  m.assert_owner_thread();
  if (m.ring) return ok();
  if (m.fd < 0)
    return m.broken ? *m.broken : Failure{Error::kNotConnected, "sim API: not connected"};
  if (!ShmStream::offered_by(m.hello))
    return Failure{Error::kUnsupported, "sim API: the server does not offer shared memory"};
  if (!ShmStream::peer_is_local(m.fd))
    return Failure{Error::kUnsupported, "sim API: shared memory needs the server on this machine"};
  auto offer = request(ShmStream::offer_request(), timeout_s);
  if (!offer) return offer.error();
  // the server writes everything after its reply into the ring: nothing more comes on the socket
  auto ring = ShmStream::open(*offer);
  if (!ring) return m.fail(ring.code(), "sim API: " + ring.message());
  m.ring = std::move(*ring);
  return ok();
}

bool SimConnection::on_shared_memory() const {
  impl_->assert_owner_thread();
  return impl_->ring != nullptr;
}

Result<nlohmann::json> SimConnection::status() { return request({{"op", "status"}}); }
Result<nlohmann::json> SimConnection::pause() { return request({{"op", "pause"}}); }
Result<nlohmann::json> SimConnection::resume() { return request({{"op", "resume"}}); }
Result<nlohmann::json> SimConnection::reset(uint64_t seed) {
  return request({{"op", "reset"}, {"seed", seed}});
}
Result<nlohmann::json> SimConnection::step_for(double sim_s, double wall_timeout_s) {
  return request({{"op", "step"}, {"duration_s", sim_s}}, wall_timeout_s);
}
Result<nlohmann::json> SimConnection::subscribe_events() {
  return request({{"op", "subscribe_events"}});
}
Result<nlohmann::json> SimConnection::truck() { return request({{"op", "truck"}}); }

Result<nlohmann::json> SimConnection::lockstep_join(double period_s, double timeout_s,
                                                    const std::vector<nlohmann::json>& with_tick) {
  Json req = {{"op", "lockstep_join"}, {"period_s", period_s}, {"timeout_s", timeout_s}};
  if (!with_tick.empty()) req["with_tick"] = with_tick;
  return request(std::move(req));
}
Result<nlohmann::json> SimConnection::lockstep_leave() {
  return request({{"op", "lockstep_leave"}});
}
Result<nlohmann::json> SimConnection::done(int64_t tick,
                                           const std::map<std::string, int>& mavlink_seq,
                                           std::optional<double> busy_until_s) {
  Json req = {{"op", "done"}, {"tick", tick}};
  if (!mavlink_seq.empty()) req["mavlink_seq"] = mavlink_seq;
  if (busy_until_s) req["busy_until"] = *busy_until_s;
  return request(std::move(req));
}

Result<nlohmann::json> SimConnection::radio_send(int vehicle, std::string_view bytes, int to) {
  Json req = {{"op", "radio_send"},
              {"vehicle", vehicle},
              {"data_b64", common::base64_encode(
                               reinterpret_cast<const std::uint8_t*>(bytes.data()), bytes.size())}};
  req["to"] = to < 0 ? Json("broadcast") : Json(to);
  return request(std::move(req));
}
Result<nlohmann::json> SimConnection::radio_subscribe(int vehicle) {
  Json req = {{"op", "radio_subscribe"}};
  if (vehicle >= 0) req["vehicle"] = vehicle;
  return request(std::move(req));
}

}  // namespace uavsim::client
