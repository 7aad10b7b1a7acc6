#include "uavsim/client/event_loop.hpp"

#include <arpa/inet.h>
#include <fcntl.h>
#include <netdb.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <sys/epoll.h>
#include <sys/eventfd.h>
#include <sys/socket.h>
#include <sys/timerfd.h>
#include <time.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <functional>
#include <limits>
#include <map>
#include <mutex>
#include <nlohmann/json.hpp>
#include <optional>
#include <sstream>
#include <thread>
#include <unordered_map>
#include <utility>
#include <vector>

#include "loop_services.hpp"
#include "net.hpp"
#include "sim_channel.hpp"
#include "uavsim/common/parse_number.hpp"

namespace uavsim::client {

namespace {

using Json = nlohmann::json;
constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kEps = 1e-9;

std::int64_t mono_ns() {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<std::int64_t>(ts.tv_sec) * 1000000000LL + ts.tv_nsec;
}

}  // namespace

// ---------------------------------------------------------------- config

LoopConfig LoopConfig::host() { return LoopConfig{}; }

LoopConfig LoopConfig::lockstep(const std::string& host, int port, double period_s) {
  LoopConfig c;
  c.clock = Clock::kLockstep;
  c.lockstep_host = host;
  c.lockstep_port = port;
  c.lockstep_period_s = period_s;
  return c;
}

LoopConfig LoopConfig::from_env() {
  LoopConfig c;
  const char* env = std::getenv("UAVSIM_LOCKSTEP");
  if (env == nullptr || *env == '\0') return c;
  const char* transport = std::getenv("UAVSIM_API_TRANSPORT");
  const std::string transport_name = transport != nullptr ? transport : "";
  const auto chosen = transport_name == "tcp"   ? LoopConfig::Transport::kTcp
                      : transport_name == "shm" ? LoopConfig::Transport::kShm
                                                : LoopConfig::Transport::kAuto;
  std::string spec = env;
  double period = c.lockstep_period_s;
  // a period or port that is not a whole number in range leaves the port invalid: create() reports it
  bool ok = true;
  if (const auto slash = spec.find('/'); slash != std::string::npos) {
    ok = common::parse_double(spec.c_str() + slash + 1, 1e-4, 10.0, &period);
    spec.resize(slash);
  }
  const auto colon = spec.rfind(':');
  int port = -1;
  if (colon == std::string::npos || !ok || !common::parse_integer(spec.c_str() + colon + 1, 1, 65535, &port)) {
    c.clock = Clock::kLockstep;
    c.lockstep_port = -1;  // reported by create()
    return c;
  }
  c = lockstep(spec.substr(0, colon), port, period);
  c.lockstep_transport = chosen;
  return c;
}

// ---------------------------------------------------------------- Impl

struct EventLoop::Impl {
  struct Timer {
    double deadline = 0.0;
    double period = 0.0;  // 0: one-shot
    std::shared_ptr<Task> fn;
  };
  struct Watch {
    std::uint32_t events = 0;
    std::shared_ptr<std::function<void(std::uint32_t)>> fn;
  };
  using SeqSource = LoopServices::SeqSource;

  LoopConfig config;
  std::thread::id thread;
  int epfd = -1;
  // lockstep: the readable side of the watched descriptors, read just before a tick applies
  // (read_links) rather than whenever bytes arrive, so every run sees the same bytes at the same
  // tick
  int links_epfd = -1;
  int timerfd = -1;
  int wakefd = -1;
  std::int64_t start_mono_ns = 0;

  std::map<TimerId, Timer> timers;
  TimerId next_timer_id = 1;
  std::unordered_map<int, Watch> watches;
  std::mutex posted_mutex;
  std::vector<Task> posted;
  std::atomic<bool> stop_requested{false};

  // lockstep: the simulator connection (the modules' requests and sinks ride on it; the loop
  // handles what they do not take: ticks, lockstep_dropped, reset, the replies to `done`)
  SimChannel api;
  bool alive = true;
  std::string dead_reason;
  double sim_now = 0.0;
  double period_s = 0.0;
  std::int64_t tick = -1;
  bool tick_outstanding = false;
  std::optional<double> pending_busy_until;
  // from the server's replies to `done`: does it wait for the MAVLink seqs named there (api::SeqWaiter)?
  std::optional<bool> mavlink_seq_checked;
  std::map<std::uint64_t, SeqSource> seq_sources;
  std::uint64_t next_seq_source = 1;
  // pipelined lockstep (EventLoop::set_lockstep_pipelined): `done` of the current tick already sent;
  // outputs held until the next tick (requests on the lockstep connection in the SimChannel, each
  // Vehicle link's MAVLink in its own buffer, sent by its flusher)
  bool pipelined = false;
  bool done_sent = false;
  bool outputs_held = false;
  // ... and the lockstep connection is not read past the tick until the tick's work is done (the
  // next tick may already be on its way: the simulation did not wait)
  bool api_held = false;
  std::map<std::uint64_t, std::function<void()>> output_flushers;
  std::uint64_t next_output_flusher = 1;

  ~Impl();
  double now() const;
  // Handles what is ready, runs posted tasks and due timers; under lockstep answers the tick when nothing
  // is left to do at this time. With may_block, then waits for something to happen (at most until
  // wake_at on the loop clock, if finite). Returns false when nothing happened.
  bool iterate(bool may_block, double wake_at);
  bool dispatch(int timeout_ms);
  bool run_posted();
  bool run_due_timers();
  void arm_timerfd(double wake_at);
  void on_api_readable();
  // lockstep: handles what has arrived on the watched descriptors, at the clock of the tick now
  // ending
  void read_links();
  // the epoll interest of a watched descriptor: in epfd (all of it on the host clock; under
  // lockstep only writability, errors aside) and in links_epfd (readability, under lockstep)
  std::uint32_t main_interest(std::uint32_t events) const;
  std::uint32_t links_interest(std::uint32_t events) const;
  void notify_watch(int fd, std::uint32_t epoll_events);
  // what the modules' sinks and reply handlers on the lockstep connection do not take
  void on_unrouted(const nlohmann::json& j);
  void send_done();
  // pipelined lockstep, at a tick: sends the outputs held since the last tick ...
  void release_held_outputs();
  // ... then answers `done` before the tick's work, and holds what the work sends
  void answer_early();
  // pipelined lockstep: stops / resumes reading the lockstep connection (see api_held)
  void hold_api();
  void resume_api();
  std::uint32_t api_interest() const { return api_held ? 0u : (EPOLLIN | EPOLLRDHUP); }
  void update_api_interest();  // epfd's interest in the lockstep connection := api_interest()
  void lose_clock(const std::string& why);
  // create(): connects the lockstep connection, on the shared-memory stream if use_shm and the
  // server is on this machine and offers it, and joins (the first tick handled). *shm_unusable when
  // the offered stream could not be opened: the connection is unusable, connect again without it.
  Result<void> connect_and_join(bool use_shm, bool* shm_unusable);
  // create(): reads the lockstep connection (wall timeout each wait) until done() or a failure
  Result<void> read_api_until(const std::function<bool()>& done, const std::string& what);
};

EventLoop::Impl::~Impl() {
  for (int fd : {epfd, links_epfd, timerfd, wakefd}) {
    if (fd >= 0) ::close(fd);
  }
}

double EventLoop::Impl::now() const {
  if (config.clock == LoopConfig::Clock::kLockstep) return sim_now;
  return static_cast<double>(mono_ns() - start_mono_ns) * 1e-9;
}

bool EventLoop::Impl::dispatch(int timeout_ms) {
  epoll_event evs[64];
  int n;
  do {
    n = epoll_wait(epfd, evs, 64, timeout_ms);
  } while (n < 0 && errno == EINTR);
  if (n <= 0) return false;
  bool handled = false;
  for (int i = 0; i < n; ++i) {
    const int fd = evs[i].data.fd;
    if (fd == wakefd || fd == timerfd) {
      std::uint64_t v;
      [[maybe_unused]] ssize_t r = ::read(fd, &v, sizeof(v));
      handled = true;
      continue;
    }
    if (fd == api.fd()) {
      // held (pipelined, working on a tick): a hang-up is reported even with no interest; it is
      // read once the tick's work is done, and is no progress now (or the loop would spin)
      if (api_held) continue;
      on_api_readable();
      handled = true;
      continue;
    }
    notify_watch(fd, evs[i].events);
    handled = true;
  }
  return handled;
}

void EventLoop::Impl::notify_watch(int fd, std::uint32_t epoll_events) {
  auto it = watches.find(fd);
  if (it == watches.end()) return;  // unwatched by an earlier callback of this batch
  std::uint32_t what = 0;
  if (epoll_events & (EPOLLIN | EPOLLRDHUP)) what |= kReadable;
  if (epoll_events & EPOLLOUT) what |= kWritable;
  if (epoll_events & (EPOLLERR | EPOLLHUP)) what |= kError | kReadable;
  auto fn = it->second.fn;  // keeps the callback alive if it unwatches itself
  (*fn)(what);
}

std::uint32_t EventLoop::Impl::main_interest(std::uint32_t events) const {
  const std::uint32_t out = (events & kWritable) ? EPOLLOUT : 0u;
  if (links_epfd >= 0) return out;
  return EPOLLRDHUP | ((events & kReadable) ? EPOLLIN : 0u) | out;
}

std::uint32_t EventLoop::Impl::links_interest(std::uint32_t events) const {
  return (events & kReadable) ? (EPOLLIN | EPOLLRDHUP) : 0u;
}

void EventLoop::Impl::read_links() {
  if (links_epfd < 0) return;
  epoll_event evs[64];
  // bounded: a peer that never stops sending is read again at the next tick
  for (int round = 0; round < 64; ++round) {
    int n;
    do {
      n = epoll_wait(links_epfd, evs, 64, 0);
    } while (n < 0 && errno == EINTR);
    if (n <= 0) return;
    for (int i = 0; i < n; ++i) notify_watch(evs[i].data.fd, evs[i].events);
  }
}

bool EventLoop::Impl::run_posted() {
  std::vector<Task> tasks;
  {
    std::lock_guard lock(posted_mutex);
    tasks.swap(posted);
  }
  for (Task& t : tasks) t();
  return !tasks.empty();
}

bool EventLoop::Impl::run_due_timers() {
  bool ran = false;
  // bounded: a timer re-armed at the current time runs at the next iteration, not forever now
  for (int budget = 10000; budget > 0; --budget) {
    const double t = now();
    auto best = timers.end();
    for (auto it = timers.begin(); it != timers.end(); ++it) {
      if (it->second.deadline > t + kEps) continue;
      if (best == timers.end() || it->second.deadline < best->second.deadline) best = it;
    }
    if (best == timers.end()) break;
    std::shared_ptr<Task> fn = best->second.fn;
    if (best->second.period > 0.0) {
      Timer& tm = best->second;
      tm.deadline += tm.period;
      if (tm.deadline <= t + kEps) tm.deadline += std::ceil((t - tm.deadline) / tm.period + kEps) * tm.period;
      if (tm.deadline <= t + kEps) tm.deadline = t + tm.period;
    } else {
      timers.erase(best);
    }
    (*fn)();
    ran = true;
  }
  return ran;
}

void EventLoop::Impl::arm_timerfd(double wake_at) {
  for (const auto& [id, tm] : timers) wake_at = std::min(wake_at, tm.deadline);
  itimerspec spec{};
  if (std::isfinite(wake_at)) {
    std::int64_t abs_ns = start_mono_ns + static_cast<std::int64_t>(std::ceil(wake_at * 1e9));
    abs_ns = std::max<std::int64_t>(abs_ns, 1);
    spec.it_value.tv_sec = abs_ns / 1000000000LL;
    spec.it_value.tv_nsec = abs_ns % 1000000000LL;
  }
  timerfd_settime(timerfd, TFD_TIMER_ABSTIME, &spec, nullptr);
}

bool EventLoop::Impl::iterate(bool may_block, double wake_at) {
  bool progress = dispatch(0);
  progress |= run_posted();
  progress |= run_due_timers();
  if (progress) return true;
  const bool lockstep = config.clock == LoopConfig::Clock::kLockstep;
  // nothing left to do at this time: the process is waiting, so the tick is complete (seed 6.5)
  if (lockstep && tick_outstanding) send_done();
  // pipelined: the tick's work is done, so what came after the tick may be handled now
  if (lockstep && api_held && alive) {
    resume_api();
    return true;
  }
  if (!may_block) return false;
  bool got = false;
  if (!lockstep) {
    arm_timerfd(wake_at);
    got = dispatch(-1);
  } else {
    if (!alive) return false;
    const int ms = static_cast<int>(std::min(config.lockstep_wall_timeout_s, 3600.0) * 1000.0);
    got = dispatch(ms);
    if (!got && !tick_outstanding) {
      lose_clock("no tick from the simulator for " + std::to_string(config.lockstep_wall_timeout_s) +
                 " s of wall time");
    }
  }
  // what is due now runs before the caller looks at the clock (a tick's timers belong to that tick)
  run_posted();
  run_due_timers();
  return got;
}

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
  switch (api.resume_input(&why)) {
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

void EventLoop::Impl::send_done() {
  if (done_sent) {  // pipelined: answered when the tick came
    tick_outstanding = false;
    return;
  }
  Json done = {{"op", "done"}, {"tick", tick}};
  Json seqs = Json::object();
  for (const auto& [id, src] : seq_sources) {
    if (auto s = src()) seqs[s->first] = s->second;
  }
  if (!seqs.empty()) done["mavlink_seq"] = seqs;
  if (pending_busy_until) done["busy_until"] = *pending_busy_until;
  pending_busy_until.reset();
  tick_outstanding = false;
  // straight to the socket: never held with the outputs
  if (!api.send_now(done.dump())) {
    lose_clock("cannot send done to the simulator");
  }
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
  switch (api.read_available(&why)) {
    case SimChannel::ReadResult::kOk: return;
    case SimChannel::ReadResult::kClosed: lose_clock("the simulator closed the connection"); return;
    case SimChannel::ReadResult::kError: lose_clock(why); return;
  }
}

void EventLoop::Impl::on_unrouted(const Json& j) {
  if (j.contains("event")) {
    const std::string ev = j["event"].is_string() ? j["event"].get<std::string>() : "";
    if (ev == "tick") {
      // the server flushed the MAVLink bytes of the steps before this tick before it sent the tick:
      // they are handled now, at the clock of the tick before, wherever epoll would have put them
      // in this batch
      read_links();
      if (!alive) return;
      tick = j.value("tick", std::int64_t{0});
      sim_now = j.value("time", sim_now);
      tick_outstanding = true;
      done_sent = false;
      if (outputs_held) release_held_outputs();  // what the last tick's work sent: it applies now
      if (pipelined && alive) answer_early();
    } else if (ev == "lockstep_dropped") {
      lose_clock("the simulator dropped this client: " + j.value("reason", std::string("?")));
    } else if (ev == "reset") {
      std::fprintf(stderr, "uavsim client: the simulation was reset (seed %s)\n", j.value("seed", Json()).dump().c_str());
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
                 e.value("code", std::string("?")).c_str(), e.value("message", std::string("?")).c_str());
  }
}

Result<void> EventLoop::Impl::read_api_until(const std::function<bool()>& done,
                                             const std::string& what) {
  const double wall = config.lockstep_wall_timeout_s;
  const int ms = static_cast<int>(std::min(wall, 3600.0) * 1000.0);
  while (!done()) {
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
  const auto ops = h.find("ops");
  const bool offered = ops != h.end() && ops->is_array() &&
                       std::find(ops->begin(), ops->end(), "lockstep_shm") != ops->end();
  const bool local = ShmStream::peer_is_local(*fd);
  if (config.lockstep_transport == LoopConfig::Transport::kShm && (!offered || !local)) {
    return R::fail(
        Error::kUnsupported,
        std::string("lockstep: shared memory required (UAVSIM_API_TRANSPORT=shm), but ") +
            (local ? "the server does not offer it" : "the server is not on this machine"));
  }
  if (use_shm && offered && local) {
    std::optional<Json> reply;
    if (!api.request({{"op", "lockstep_shm"}, {"ring_bytes", ShmStream::kRingBytes}},
                     [&reply](const Json& j) { reply = j; })) {
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
    }
  }
  // the join's reply, then the first tick
  std::optional<Json> join;
  if (!api.request({{"op", "lockstep_join"}, {"period_s", config.lockstep_period_s}},
                   [&join](const Json& j) { join = j; })) {
    return R::fail(Error::kIo, "lockstep: cannot send the join");
  }
  if (auto r = read_api_until([&] { return join.has_value(); }, "waiting for the join's reply"); !r)
    return r;
  if ((*join)["ok"] != true)
    return R::fail(Error::kDenied, "lockstep: join refused: " + join->dump());
  const Json result = join->value("result", Json::object());
  period_s = result.value("period_s", config.lockstep_period_s);
  sim_now = std::max(0.0, result.value("first_tick_time", 0.0) - period_s);
  return read_api_until([this] { return tick_outstanding; }, "waiting for the first tick");
}

// ---------------------------------------------------------------- EventLoop

EventLoop::EventLoop(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
EventLoop::~EventLoop() = default;

Result<std::unique_ptr<EventLoop>> EventLoop::create(const LoopConfig& config) {
  auto impl = std::make_unique<Impl>();
  impl->config = config;
  impl->thread = std::this_thread::get_id();
  impl->start_mono_ns = mono_ns();
  impl->epfd = epoll_create1(EPOLL_CLOEXEC);
  impl->timerfd = timerfd_create(CLOCK_MONOTONIC, TFD_NONBLOCK | TFD_CLOEXEC);
  impl->wakefd = eventfd(0, EFD_NONBLOCK | EFD_CLOEXEC);
  if (config.clock == LoopConfig::Clock::kLockstep) impl->links_epfd = epoll_create1(EPOLL_CLOEXEC);
  if (impl->epfd < 0 || impl->timerfd < 0 || impl->wakefd < 0 ||
      (config.clock == LoopConfig::Clock::kLockstep && impl->links_epfd < 0)) {
    return Result<std::unique_ptr<EventLoop>>::fail(Error::kIo, std::string("event loop: ") + std::strerror(errno));
  }
  for (int fd : {impl->timerfd, impl->wakefd}) {
    epoll_event ev{};
    ev.events = EPOLLIN;
    ev.data.fd = fd;
    epoll_ctl(impl->epfd, EPOLL_CTL_ADD, fd, &ev);
  }

  if (config.clock == LoopConfig::Clock::kLockstep) {
    using R = Result<std::unique_ptr<EventLoop>>;
    if (config.lockstep_port <= 0 || config.lockstep_port > 65535) {
      return R::fail(Error::kInvalidArgument, "lockstep: no valid port (UAVSIM_LOCKSTEP=host:port[/period_s])");
    }
    if (!(config.lockstep_period_s > 0.0)) return R::fail(Error::kInvalidArgument, "lockstep: period must be > 0");
    // the shared-memory stream unless the environment says TCP; if the server offered one this
    // process cannot open, again on TCP
    const bool use_shm = config.lockstep_transport != LoopConfig::Transport::kTcp;
    bool shm_unusable = false;
    auto joined = impl->connect_and_join(use_shm, &shm_unusable);
    if (!joined && shm_unusable && config.lockstep_transport == LoopConfig::Transport::kAuto) {
      std::fprintf(stderr, "uavsim client: %s; lockstep over TCP\n", joined.message().c_str());
      impl->api.close();
      joined = impl->connect_and_join(false, &shm_unusable);
    }
    if (!joined) return R(joined.error());
    epoll_event ev{};
    ev.events = impl->api_interest();  // pipelined: held at the first tick
    ev.data.fd = impl->api.fd();
    epoll_ctl(impl->epfd, EPOLL_CTL_ADD, impl->api.fd(), &ev);
  }
  return std::unique_ptr<EventLoop>(new EventLoop(std::move(impl)));
}

double EventLoop::now() const { return impl_->now(); }
bool EventLoop::is_lockstep() const { return impl_->config.clock == LoopConfig::Clock::kLockstep; }
bool EventLoop::clock_alive() const { return impl_->alive; }

TimerId EventLoop::call_after(double delay_s, Task fn) {
  assert_in_loop_thread();
  const TimerId id = impl_->next_timer_id++;
  impl_->timers[id] = Impl::Timer{now() + std::max(0.0, delay_s), 0.0, std::make_shared<Task>(std::move(fn))};
  return id;
}

TimerId EventLoop::call_every(double period_s, Task fn) {
  assert_in_loop_thread();
  const TimerId id = impl_->next_timer_id++;
  period_s = std::max(period_s, 1e-6);
  impl_->timers[id] = Impl::Timer{now() + period_s, period_s, std::make_shared<Task>(std::move(fn))};
  return id;
}

bool EventLoop::cancel(TimerId id) {
  assert_in_loop_thread();
  return impl_->timers.erase(id) > 0;
}

Result<void> EventLoop::watch_fd(int fd, std::uint32_t events, std::function<void(std::uint32_t)> fn) {
  assert_in_loop_thread();
  epoll_event ev{};
  ev.events = impl_->main_interest(events);
  ev.data.fd = fd;
  if (epoll_ctl(impl_->epfd, EPOLL_CTL_ADD, fd, &ev) != 0) {
    return Result<void>::fail(Error::kIo, std::string("epoll_ctl ADD: ") + std::strerror(errno));
  }
  if (impl_->links_epfd >= 0) {
    ev.events = impl_->links_interest(events);
    if (epoll_ctl(impl_->links_epfd, EPOLL_CTL_ADD, fd, &ev) != 0) {
      const int err = errno;
      epoll_ctl(impl_->epfd, EPOLL_CTL_DEL, fd, nullptr);
      return Result<void>::fail(Error::kIo, std::string("epoll_ctl ADD: ") + std::strerror(err));
    }
  }
  impl_->watches[fd] = Impl::Watch{events, std::make_shared<std::function<void(std::uint32_t)>>(std::move(fn))};
  return {};
}

Result<void> EventLoop::modify_fd(int fd, std::uint32_t events) {
  assert_in_loop_thread();
  auto it = impl_->watches.find(fd);
  if (it == impl_->watches.end()) return Result<void>::fail(Error::kInvalidArgument, "modify_fd: not watched");
  if (it->second.events == events) return {};
  epoll_event ev{};
  ev.events = impl_->main_interest(events);
  ev.data.fd = fd;
  if (epoll_ctl(impl_->epfd, EPOLL_CTL_MOD, fd, &ev) != 0) {
    return Result<void>::fail(Error::kIo, std::string("epoll_ctl MOD: ") + std::strerror(errno));
  }
  if (impl_->links_epfd >= 0) {
    ev.events = impl_->links_interest(events);
    if (epoll_ctl(impl_->links_epfd, EPOLL_CTL_MOD, fd, &ev) != 0) {
      return Result<void>::fail(Error::kIo, std::string("epoll_ctl MOD: ") + std::strerror(errno));
    }
  }
  it->second.events = events;
  return {};
}

void EventLoop::unwatch_fd(int fd) {
  assert_in_loop_thread();
  if (impl_->watches.erase(fd) == 0) return;
  epoll_ctl(impl_->epfd, EPOLL_CTL_DEL, fd, nullptr);
  if (impl_->links_epfd >= 0) epoll_ctl(impl_->links_epfd, EPOLL_CTL_DEL, fd, nullptr);
}

void EventLoop::post(Task fn) {
  {
    std::lock_guard lock(impl_->posted_mutex);
    impl_->posted.push_back(std::move(fn));
  }
  const std::uint64_t one = 1;
  [[maybe_unused]] ssize_t r = ::write(impl_->wakefd, &one, sizeof(one));
}

void EventLoop::run() {
  assert_in_loop_thread();
  while (!impl_->stop_requested.exchange(false)) {
    if (is_lockstep() && !impl_->alive) return;
    impl_->iterate(true, kInf);
  }
  // tasks posted before stop() still run: a stop from another thread can come before the loop has
  // woken up for the tasks that thread posted first
  impl_->run_posted();
}

void EventLoop::stop() {
  impl_->stop_requested = true;
  post([] {});
}

Result<void> EventLoop::run_for(double duration_s) {
  assert_in_loop_thread();
  const double deadline = now() + std::max(0.0, duration_s);
  while (now() < deadline - kEps || (is_lockstep() && impl_->alive && !impl_->tick_outstanding)) {
    if (is_lockstep() && !impl_->alive) {
      return Result<void>::fail(Error::kConnectionLost, "lockstep clock lost: " + impl_->dead_reason);
    }
    impl_->iterate(true, deadline);
  }
  return {};
}

Result<void> EventLoop::run_until(const std::function<bool()>& pred, double timeout_s, const std::string& what) {
  assert_in_loop_thread();
  if (pred()) return {};
  const double start = now();
  const double deadline = start + std::max(0.0, timeout_s);
  for (;;) {
    if (is_lockstep() && !impl_->alive) {
      return Result<void>::fail(Error::kConnectionLost,
                                "lockstep clock lost while waiting for " + what + ": " + impl_->dead_reason);
    }
    impl_->iterate(true, deadline);
    // lockstep: the caller resumes at a tick (the simulation held), never between two, so what it does next
    // happens at a defined sim time; data that arrived in between is in the caches by then
    if (is_lockstep() && impl_->alive && !impl_->tick_outstanding) continue;
    if (pred()) return {};
    if (now() >= deadline - kEps) {
      std::ostringstream os;
      os << "timed out after " << timeout_s << " s waiting for " << what;
      return Result<void>::fail(Error::kTimeout, os.str());
    }
  }
}

void EventLoop::run_busy(double duration_s, const std::function<void()>& fn) {
  assert_in_loop_thread();
  if (!is_lockstep() || !impl_->alive) {
    fn();
    return;
  }
  if (impl_->pipelined) {  // answered at every tick: no detaching
    fn();
    (void)run_for(duration_s);
    return;
  }
  // the busy section starts at a tick: the current one, or the next
  if (!impl_->tick_outstanding) {
    (void)run_until([this] { return impl_->tick_outstanding || !impl_->alive; }, kInf, "the next tick");
    if (!impl_->alive) {
      fn();
      return;
    }
  }
  const double until = now() + std::max(0.0, duration_s);
  impl_->pending_busy_until = until;
  impl_->send_done();
  fn();
  (void)run_until([&] { return now() >= until - kEps; }, kInf, "the end of a busy section");
}

void EventLoop::set_lockstep_pipelined(bool on) {
  assert_in_loop_thread();
  impl_->pipelined = on && is_lockstep();
}

bool EventLoop::lockstep_pipelined() const { return impl_->pipelined; }

bool EventLoop::in_loop_thread() const { return std::this_thread::get_id() == impl_->thread; }

void EventLoop::assert_in_loop_thread() const {
  if (in_loop_thread()) return;
  std::ostringstream os;
  os << std::this_thread::get_id();
  std::fprintf(stderr,
               "uavsim client: EventLoop used from thread %s, not from its loop thread (use EventLoop::post)\n",
               os.str().c_str());
  std::abort();
}

// ---------------------------------------------------------------- LoopServices

SimChannel* LoopServices::sim_channel() const {
  return impl_.config.clock == LoopConfig::Clock::kLockstep ? &impl_.api : nullptr;
}

std::uint64_t LoopServices::add_seq_source(SeqSource source) {
  impl_.seq_sources[impl_.next_seq_source] = std::move(source);
  return impl_.next_seq_source++;
}

void LoopServices::remove_seq_source(std::uint64_t id) { impl_.seq_sources.erase(id); }

bool LoopServices::outputs_held() const { return impl_.outputs_held; }

std::uint64_t LoopServices::add_output_flusher(std::function<void()> flush) {
  impl_.output_flushers[impl_.next_output_flusher] = std::move(flush);
  return impl_.next_output_flusher++;
}

void LoopServices::remove_output_flusher(std::uint64_t id) { impl_.output_flushers.erase(id); }

std::optional<bool> LoopServices::mavlink_seq_checked() const { return impl_.mavlink_seq_checked; }

}  // namespace uavsim::client
