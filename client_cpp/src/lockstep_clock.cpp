// The lockstep clock of an EventLoop (docs/protocol.md, "Lockstep contract"): joining the simulator
// (over TCP or its shared-memory stream), taking its ticks, answering `done` with the MAVLink seqs
// of the vehicle links, and the pipelined mode's held outputs. The reactor in event_loop.cpp calls
// these; none of it runs on the host clock.
#include <poll.h>
#include <sys/epoll.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>

#include "event_loop_impl.hpp"
#include "net.hpp"
#include "uavsim/common/shm_requests.hpp"

namespace uavsim::client {

using Json = nlohmann::json;

void EventLoop::Impl::release_held_outputs() {
  outputs_held = false;
  // a flusher may close its link (and unregister): iterate over a copy
  const auto flushers = output_flushers;
  for (const auto& [id, flush] : flushers) flush();
  if (!api.release_outputs()) lose_clock("cannot send to the simulator");
}

void EventLoop::Impl::answer_early() {
  send_done();
  if (!alive) return;
  tick_outstanding = true;  // the caller is still at this tick: its work for it comes now
  done_sent = true;
  outputs_held = true;
  api.hold_outputs();
  hold_api();
}

void EventLoop::Impl::update_api_interest() {
  if (!api.is_open()) return;
  epoll_event ev{};
  ev.events = api_interest();
  ev.data.fd = api.fd();
  epoll_ctl(epfd, EPOLL_CTL_MOD, api.fd(), &ev);  // fails harmlessly before create() has added it
}

void EventLoop::Impl::hold_api() {
  api_held = true;
  api.hold_input();
  update_api_interest();
}

void EventLoop::Impl::resume_api() {
  api_held = false;
  update_api_interest();
  std::string why;
  after_read(api.resume_input(&why), why);
}

void EventLoop::Impl::send_done() {
  if (done_sent) {  // pipelined: answered when the tick came
    tick_outstanding = false;
    return;
  }
  // the MAVLink seqs the server must have handled before this tick ends (by vehicle key)
  std::vector<std::pair<std::string, int>> seqs;
  for (const auto& [id, src] : seq_sources) {
    if (auto s = src()) seqs.push_back(std::move(*s));
  }
  const std::optional<double> busy_until = pending_busy_until;
  pending_busy_until.reset();
  tick_outstanding = false;
  // straight to the server: never held with the outputs
  const bool sent = api.has_request_ring() ? send_done_record(seqs, busy_until)
                                           : send_done_line(seqs, busy_until);
  // the done wakes the server for it and the tick's requests before it, whatever the loop does next
  // (run_busy works on without sleeping)
  api.flush_request_wakeup();
  if (!sent) lose_clock("cannot send done to the simulator");
}

bool EventLoop::Impl::send_done_record(const std::vector<std::pair<std::string, int>>& seqs,
                                       std::optional<double> busy_until) {
  // the binary done (common/shm_requests.hpp): quiet, as this loop waits for its next tick, never
  // for the reply, which comes only if the server refuses the done. Vehicles named by name rather
  // than index have no binary form: such a done goes as its line.
  common::shm::DoneRecord d;
  d.quiet = true;
  d.tick = tick;
  d.busy_until_s = busy_until;
  for (const auto& [key, seq] : seqs) {
    char* end = nullptr;
    const unsigned long vehicle = std::strtoul(key.c_str(), &end, 10);
    if (key.empty() || *end != '\0' || vehicle >= common::shm::kMaxVehicleIndex || seq < 0 ||
        seq > 255) {
      return send_done_line(seqs, busy_until);
    }
    d.mavlink_seq.emplace_back(static_cast<std::uint32_t>(vehicle), static_cast<std::uint8_t>(seq));
  }
  done_record.clear();
  common::shm::encode_done(d, &done_record);
  return api.send_binary(common::shm::RecordType::kDone, done_record);
}

bool EventLoop::Impl::send_done_line(const std::vector<std::pair<std::string, int>>& seqs,
                                     std::optional<double> busy_until) {
  Json done = {{"op", "done"}, {"tick", tick}};
  Json seq_map = Json::object();
  for (const auto& [key, seq] : seqs) seq_map[key] = seq;
  if (!seq_map.empty()) done["mavlink_seq"] = seq_map;
  if (busy_until) done["busy_until"] = *busy_until;
  // this loop waits for its next tick, never for this reply: on the shared-memory stream the server
  // need not wake it before that tick (docs/protocol.md, "Shared-memory stream")
  if (api.on_ring()) done["quiet"] = true;
  return api.send_now(done.dump());
}

void EventLoop::Impl::lose_clock(const std::string& why) {
  if (!alive) return;
  alive = false;
  tick_outstanding = false;
  outputs_held = false;
  dead_reason = why;
  std::fprintf(stderr, "uavsim client: lockstep clock lost: %s\n", why.c_str());
  if (api.is_open()) {
    epoll_ctl(epfd, EPOLL_CTL_DEL, api.fd(), nullptr);
    api.close();  // and what it held
  }
}

void EventLoop::Impl::on_api_readable() {
  if (api_held) return;
  std::string why;
  after_read(api.read_available(&why), why);
}

void EventLoop::Impl::after_read(SimChannel::ReadResult r, const std::string& why) {
  switch (r) {
    case SimChannel::ReadResult::kOk:
      return;
    case SimChannel::ReadResult::kClosed:
      lose_clock("the simulator closed the connection");
      return;
    case SimChannel::ReadResult::kError:
      lose_clock(why);
      return;
  }
}

void EventLoop::Impl::on_tick(std::int64_t n, double time_s) {
  // the server flushed the MAVLink bytes of the steps before this tick before it sent the tick:
  // they are handled now, at the clock of the tick before, wherever epoll would have put them in
  // this batch
  read_links();
  if (!alive) return;
  tick = n;
  sim_now = time_s;
  tick_outstanding = true;
  done_sent = false;
  if (outputs_held) release_held_outputs();  // what the last tick's work sent: it applies now
  if (pipelined && alive) answer_early();
}

void EventLoop::Impl::on_unrouted(const Json& j) {
  if (j.contains("event")) {
    const std::string ev = j["event"].is_string() ? j["event"].get<std::string>() : "";
    if (ev == "tick") {
      on_tick(j.value("tick", std::int64_t{0}), j.value("time", sim_now));
    } else if (ev == "lockstep_dropped") {
      lose_clock("the simulator dropped this client: " + j.value("reason", std::string("?")));
    } else if (ev == "reset") {
      std::fprintf(stderr, "uavsim client: the simulation was reset (seed %s)\n",
                   j.value("seed", Json()).dump().c_str());
    }
    return;
  }
  if (j.contains("ok") && j["ok"] == true && j.contains("result") && j["result"].is_object() &&
      j["result"].contains("mavlink_seq_checked")) {
    mavlink_seq_checked = j["result"]["mavlink_seq_checked"] == true;
  }
  if (j.contains("ok") && j["ok"] == false) {
    const Json e = j.value("error", Json::object());
    std::fprintf(stderr, "uavsim client: lockstep request refused: %s: %s\n",
                 e.value("code", std::string("?")).c_str(),
                 e.value("message", std::string("?")).c_str());
  }
}

Result<void> EventLoop::Impl::read_api_until(const std::function<bool()>& done,
                                             const std::string& what) {
  const double wall = config.lockstep_wall_timeout_s;
  const int ms = static_cast<int>(std::min(wall, 3600.0) * 1000.0);
  while (!done()) {
    api.flush_request_wakeup();
    pollfd p{api.fd(), POLLIN, 0};
    int n;
    do {
      n = ::poll(&p, 1, ms);
    } while (n < 0 && errno == EINTR);
    if (n == 0)
      return Result<void>::fail(
          Error::kTimeout, "lockstep: " + what + ": nothing for " + std::to_string(wall) + " s");
    if (n < 0)
      return Result<void>::fail(Error::kIo, "lockstep: " + what + ": " + std::strerror(errno));
    on_api_readable();
    if (!alive)
      return Result<void>::fail(Error::kConnectionLost, "lockstep: " + what + ": " + dead_reason);
  }
  return {};
}

Result<void> EventLoop::Impl::connect_and_join(bool use_shm, bool* shm_unusable) {
  using R = Result<void>;
  const double wall = config.lockstep_wall_timeout_s;
  auto fd = net::tcp_connect(config.lockstep_host, config.lockstep_port, wall);
  if (!fd) return R(Failure{fd.code(), "lockstep: simulator API: " + fd.message()});
  api.open(*fd, wall, [this](const Json& j) { on_unrouted(j); });
  std::string buf;
  auto hello = net::read_line(*fd, buf, wall);
  if (!hello)
    return R(
        Failure{hello.code(), "lockstep: no hello from the simulator API: " + hello.message()});
  const Json h = Json::parse(*hello, nullptr, false);
  if (!h.is_object() || h.value("hello", std::string()) != "uavsim") {
    return R::fail(Error::kProtocol, "lockstep: not a uavsim simulator API: " + *hello);
  }
  if (!buf.empty()) api.feed(buf.data(), buf.size());
  // the shared-memory stream: for a server on this machine that serves it; a server that does not
  // (an older one, a remote one) answers with an error and the connection goes on over TCP
  const bool offered = ShmStream::offered_by(h);
  const bool local = ShmStream::peer_is_local(*fd);
  if (config.lockstep_transport == LoopConfig::Transport::kShm && (!offered || !local)) {
    return R::fail(
        Error::kUnsupported,
        std::string("lockstep: shared memory required (UAVSIM_API_TRANSPORT=shm), but ") +
            (local ? "the server does not offer it" : "the server is not on this machine"));
  }
  if (use_shm && offered && local) {
    std::optional<Json> reply;
    if (!api.request(ShmStream::offer_request(), [&reply](const Json& j) { reply = j; })) {
      return R::fail(Error::kIo, "lockstep: cannot send to the simulator");
    }
    if (auto r = read_api_until([&] { return reply.has_value(); },
                                "waiting for the shared-memory offer");
        !r)
      return r;
    if (reply->value("ok", false) != true &&
        config.lockstep_transport == LoopConfig::Transport::kShm) {
      return R::fail(Error::kDenied, "lockstep: shared memory required, the server refused: " +
                                         reply_error_text(*reply));
    }
    if (reply->value("ok", false) == true) {
      // the server writes everything after this reply into the ring
      auto ring = ShmStream::open(reply->value("result", Json::object()));
      if (!ring) {
        *shm_unusable = true;
        return R(ring.error());
      }
      api.use_ring(std::move(*ring));
      // its tick records' ticks come straight here, not as tick messages
      api.set_tick_handler([this](std::int64_t n, double time_s) { on_tick(n, time_s); });
      // every wait of this loop wakes the server first (dispatch, read_api_until)
      api.defer_request_wakeups();
    }
  }
  // the join's reply, then the first tick. The clock before that tick is set while the reply is
  // read: the tick may come in the same read, right behind the reply, and its time must not be
  // overwritten afterwards by this earlier one (a loaded machine did so, and the client then ran
  // one period behind the server's clock)
  std::optional<Json> join;
  const auto on_join = [this, &join](const Json& j) {
    join = j;
    if (j.value("ok", false) != true) return;
    const Json result = j.value("result", Json::object());
    // (a binary done is not answered: the join says whether the server waits for MAVLink seqs)
    if (result.contains("mavlink_seq_checked") && result["mavlink_seq_checked"].is_boolean())
      mavlink_seq_checked = result["mavlink_seq_checked"].get<bool>();
    period_s = result.value("period_s", config.lockstep_period_s);
    sim_now = std::max(0.0, result.value("first_tick_time", 0.0) - period_s);
  };
  if (!api.request({{"op", "lockstep_join"}, {"period_s", config.lockstep_period_s}}, on_join)) {
    return R::fail(Error::kIo, "lockstep: cannot send the join");
  }
  if (auto r = read_api_until([&] { return join.has_value(); }, "waiting for the join's reply"); !r)
    return r;
  if ((*join)["ok"] != true)
    return R::fail(Error::kDenied, "lockstep: join refused: " + join->dump());
  return read_api_until([this] { return tick_outstanding; }, "waiting for the first tick");
}

}  // namespace uavsim::client
