#include "sim_channel.hpp"

#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <optional>
#include <utility>
#include <vector>

#include "net.hpp"

namespace uavsim::client {

SimChannel::~SimChannel() { close(); }

void SimChannel::open(int fd, double send_timeout_s, Unrouted unrouted) {
  close();
  fd_ = fd;
  send_timeout_s_ = send_timeout_s;
  unrouted_ = std::move(unrouted);
}

Result<std::unique_ptr<SimChannel>> SimChannel::connect(EventLoop& loop, const std::string& address,
                                                        double timeout_s) {
  using R = Result<std::unique_ptr<SimChannel>>;
  std::string host;
  int port = 0;
  if (!net::parse_address(address, &host, &port)) {
    return R::fail(Error::kInvalidArgument, "bad simulator API address '" + address + "'");
  }
  auto fd = net::tcp_connect(host, port, timeout_s);
  if (!fd) return R(Failure{fd.code(), "simulator API: " + fd.message()});
  auto channel = std::make_unique<SimChannel>();
  channel->open(*fd, timeout_s, [](const Json&) {});
  std::string buf;
  auto hello = net::read_line(*fd, buf, timeout_s);
  if (!hello) return R(Failure{hello.code(), "no hello from the simulator API: " + hello.message()});
  SimChannel* c = channel.get();
  if (auto w = loop.watch_fd(*fd, EventLoop::kReadable, [c](std::uint32_t what) { c->on_io(what); }); !w) {
    return R(w.error());
  }
  channel->watched_by_ = &loop;
  if (!buf.empty()) channel->feed(buf.data(), buf.size());
  return channel;
}

void SimChannel::close() {
  if (fd_ < 0) return;
  if (watched_by_ != nullptr) watched_by_->unwatch_fd(fd_);
  watched_by_ = nullptr;
  ::close(fd_);
  fd_ = -1;
  ring_.reset();
  outputs_held_ = false;
  held_.clear();
  reply_handlers_.clear();
}

bool SimChannel::request(Json request, ReplyHandler on_reply) {
  if (fd_ < 0) return false;
  std::string id = std::to_string(next_request_id_++);
  id.insert(id.begin(), 'r');  // (not "r" + ...: a GCC 12 -Wrestrict false positive)
  request["id"] = id;
  reply_handlers_[id] = std::move(on_reply);
  if (!send(request.dump())) {
    reply_handlers_.erase(id);
    return false;
  }
  return true;
}

bool SimChannel::send(const std::string& line) {
  if (fd_ < 0) return false;
  if (outputs_held_) {
    held_ += line;
    held_ += '\n';
    return true;
  }
  return send_now(line);
}

bool SimChannel::send_now(const std::string& line) { return send_lines(line + "\n"); }

bool SimChannel::release_outputs() {
  outputs_held_ = false;
  if (held_.empty()) return true;
  std::string lines;
  lines.swap(held_);
  return send_lines(lines);
}

bool SimChannel::send_lines(const std::string& lines) {
  if (fd_ >= 0 && !has_request_ring()) return net::send_all(fd_, lines, send_timeout_s_);
  const auto* bytes = reinterpret_cast<const std::uint8_t*>(lines.data());
  return write_request(common::shm::RecordType::kStream, {bytes, lines.size()});
}

bool SimChannel::send_binary(common::shm::RecordType type, std::span<const std::uint8_t> payload) {
  return write_request(type, payload);
}

bool SimChannel::write_request(common::shm::RecordType type,
                               std::span<const std::uint8_t> payload) {
  if (fd_ < 0 || !has_request_ring()) return false;
  std::string why;
  if (ring_->write_request(type, payload, send_timeout_s_, &why, defer_wakeups_)) return true;
  std::fprintf(stderr, "uavsim client: sim API: %s\n", why.c_str());
  return false;
}

std::uint32_t SimChannel::add_standing_reply(ReplyHandler handler) {
  const std::uint32_t tag = next_standing_tag_++;
  standing_replies_[tag] = std::move(handler);
  return tag;
}

SimChannel::ReadResult SimChannel::read_available(std::string* why) {
  if (ring_) return read_ring(why);
  char buf[65536];
  while (fd_ >= 0 && !stream_.held()) {
    const ssize_t n = ::recv(fd_, buf, sizeof(buf), MSG_DONTWAIT);
    if (n > 0) {
      feed(buf, static_cast<std::size_t>(n));
      if (stream_.error()) {
        if (why != nullptr) *why = *stream_.error();
        return ReadResult::kError;
      }
      continue;
    }
    if (n == 0) return ReadResult::kClosed;
    if (errno == EINTR) continue;
    if (errno == EAGAIN || errno == EWOULDBLOCK) break;
    if (why != nullptr) *why = std::string("recv: ") + std::strerror(errno);
    return ReadResult::kError;
  }
  return ReadResult::kOk;
}

void SimChannel::feed(const char* data, std::size_t size) {
  stream_.feed(data, size, [this](const Json& j, std::string_view payload) { route(j, payload); });
}

SimChannel::ReadResult SimChannel::resume_input(std::string* why) {
  stream_.resume([this](const Json& j, std::string_view payload) { route(j, payload); });
  if (stream_.error()) {
    if (why != nullptr) *why = *stream_.error();
    return ReadResult::kError;
  }
  // (a socket stays readable while bytes wait; the ring's wake-up was taken already)
  return ring_ && !stream_.held() ? read_ring(why) : ReadResult::kOk;
}

SimChannel::ReadResult SimChannel::read_ring(std::string* why) {
  namespace shm = common::shm;
  const bool closed = ring_->drain_wakeups();
  std::string error;
  while (ring_ && !stream_.held()) {
    const auto status = ring_->next(&record_, &error);
    if (status == shm::RingReader::Status::kEmpty)
      return closed ? ReadResult::kClosed : ReadResult::kOk;
    if (status == shm::RingReader::Status::kCorrupt) {
      if (why != nullptr) *why = "shared-memory stream: " + error;
      return ReadResult::kError;
    }
    if (record_.type != shm::RecordType::kStream && record_.type != shm::RecordType::kTick) {
      if (why != nullptr) *why = "shared-memory stream: a request record from the server";
      return ReadResult::kError;
    }
    if (record_.type == shm::RecordType::kStream) {
      feed(reinterpret_cast<const char*>(record_.payload.data()), record_.payload.size());
      if (stream_.error()) {
        if (why != nullptr) *why = *stream_.error();
        return ReadResult::kError;
      }
    } else if (!route_tick(record_.payload, &error)) {
      if (why != nullptr) *why = "shared-memory stream: " + error;
      return ReadResult::kError;
    }
  }
  return ReadResult::kOk;  // held (or closed by a handler): the rest waits
}

bool SimChannel::route_tick(const std::vector<std::uint8_t>& payload, std::string* why) {
  // the frames that arrived since the last tick, then the tick: as radio_batch and tick on TCP.
  // Decoded into the buffers of the last tick's (taken out while in use: a handler may read on)
  common::shm::TickRecord tick;
  std::swap(tick, tick_buffer_);
  if (!common::shm::decode_tick(payload, &tick, why)) return false;
  if (!tick.frames.empty()) {
    const auto sinks = radio_sinks_;  // a sink may remove itself
    for (const auto& frame : tick.frames) {
      for (const auto& [id, sink] : sinks) sink(frame);
    }
  }
  const std::int64_t number = tick.tick;
  const double time_s = tick.time_s;
  std::swap(tick, tick_buffer_);
  if (tick_handler_) {
    tick_handler_(number, time_s);
  } else {
    route(Json{{"event", "tick"}, {"tick", number}, {"time", time_s}}, std::string_view());
  }
  return true;
}

void SimChannel::on_io(std::uint32_t what) {
  if (!(what & EventLoop::kReadable)) return;
  if (read_available(nullptr) != ReadResult::kOk) close();
}

bool SimChannel::add_frame_sink(const std::string& camera, FrameSink sink) {
  return frame_sinks_.emplace(camera, std::move(sink)).second;
}

void SimChannel::remove_frame_sink(const std::string& camera) { frame_sinks_.erase(camera); }

std::uint64_t SimChannel::add_event_sink(const std::string& event, EventSink sink) {
  const std::uint64_t id = next_event_sink_++;
  event_sinks_.emplace(event, std::make_pair(id, std::move(sink)));
  return id;
}

std::uint64_t SimChannel::add_radio_sink(RadioSink sink) {
  const std::uint64_t id = next_event_sink_++;
  radio_sinks_.emplace(id, std::move(sink));
  return id;
}

void SimChannel::remove_event_sink(std::uint64_t id) {
  if (radio_sinks_.erase(id) > 0) return;
  for (auto it = event_sinks_.begin(); it != event_sinks_.end(); ++it) {
    if (it->second.first == id) {
      event_sinks_.erase(it);
      return;
    }
  }
}

void SimChannel::route(const Json& j, std::string_view payload) {
  if (!j.is_object()) return;
  if (j.contains("event")) {
    const std::string ev = j["event"].is_string() ? j["event"].get<std::string>() : "";
    if (ev == "frame") {
      auto it = frame_sinks_.find(j.value("camera", std::string()));
      if (it != frame_sinks_.end()) {
        auto sink = it->second;  // the sink may remove itself
        sink(j, payload);
      }
      return;
    }
    const auto [first, last] = event_sinks_.equal_range(ev);
    if (first == last) {
      if (unrouted_) unrouted_(j);
      return;
    }
    std::vector<EventSink> sinks;
    for (auto it = first; it != last; ++it) sinks.push_back(it->second.second);
    for (const EventSink& sink : sinks) sink(j);
    return;
  }
  if (j.contains("id") && j["id"].is_string()) {
    const std::string& id = j["id"].get_ref<const std::string&>();
    // a binary request's refusal: "b<tag>"
    if (!id.empty() && id[0] == 'b') {
      char* end = nullptr;
      const unsigned long tag = std::strtoul(id.c_str() + 1, &end, 10);
      const auto standing = standing_replies_.find(static_cast<std::uint32_t>(tag));
      if (*end == '\0' && id.size() > 1 && standing != standing_replies_.end()) {
        auto fn = standing->second;  // the handler may remove itself
        fn(j);
        return;
      }
    }
    auto it = reply_handlers_.find(id);
    if (it != reply_handlers_.end()) {
      auto fn = std::move(it->second);
      reply_handlers_.erase(it);
      fn(j);
      return;
    }
  }
  if (unrouted_) unrouted_(j);
}

Result<nlohmann::json> call_and_wait(EventLoop& loop, SimChannel& channel, nlohmann::json request,
                                     double timeout_s, const std::string& who) {
  using R = Result<nlohmann::json>;
  const std::string op = request.value("op", std::string());
  // the reply lives here until the wait below is over (the handler runs inside run_until)
  auto reply = std::make_shared<std::optional<nlohmann::json>>();
  if (!channel.request(std::move(request), [reply](const nlohmann::json& j) { *reply = j; })) {
    return R::fail(Error::kConnectionLost, who + ": no simulator connection");
  }
  SimChannel* c = &channel;
  auto w = loop.run_until([reply, c] { return reply->has_value() || !c->is_open(); }, timeout_s, op + "'s reply");
  if (reply->has_value()) return std::move(**reply);
  if (!w) return R(w.error());
  return R::fail(Error::kConnectionLost, who + ": the simulator closed the connection");
}

std::string reply_error_text(const nlohmann::json& reply) {
  const nlohmann::json e = reply.value("error", nlohmann::json::object());
  return e.value("code", std::string("?")) + ": " + e.value("message", std::string("?"));
}

}  // namespace uavsim::client
