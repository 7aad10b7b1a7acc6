// The reactor of an EventLoop (event_loop.hpp): epoll over the watched descriptors, a timerfd on
// the host clock, posted tasks through an eventfd; and the public EventLoop API. The lockstep
// clock's protocol is in lockstep_clock.cpp, the loop's state in event_loop_impl.hpp.
#include "uavsim/client/event_loop.hpp"

#include <sys/epoll.h>
#include <sys/eventfd.h>
#include <sys/timerfd.h>
#include <time.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <sstream>
#include <utility>

#include "event_loop_impl.hpp"

namespace uavsim::client {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kEps = 1e-9;

std::int64_t mono_ns() {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<std::int64_t>(ts.tv_sec) * 1000000000LL + ts.tv_nsec;
}

}  // namespace

// ---------------------------------------------------------------- Impl: the reactor

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
  // the server is woken for this loop's requests before it sleeps (SimChannel's deferred wake-ups)
  if (timeout_ms != 0) api.flush_request_wakeup();
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
      if (tm.deadline <= t + kEps)
        tm.deadline += std::ceil((t - tm.deadline) / tm.period + kEps) * tm.period;
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
  // pipelined: the tick's work is done, so what came after the tick may be handled now. If the next
  // tick is there already, its timers run now too, as when it is waited for below: whether it came
  // before or after this point is the machine's timing, and the caller may look at the clock next
  if (lockstep && api_held && alive) {
    resume_api();
    run_posted();
    run_due_timers();
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
      lose_clock("no tick from the simulator for " +
                 std::to_string(config.lockstep_wall_timeout_s) + " s of wall time");
    }
  }
  // what is due now runs before the caller looks at the clock (a tick's timers belong to that tick)
  run_posted();
  run_due_timers();
  return got;
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
    return Result<std::unique_ptr<EventLoop>>::fail(
        Error::kIo, std::string("event loop: ") + std::strerror(errno));
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
      return R::fail(Error::kInvalidArgument,
                     "lockstep: no valid port (UAVSIM_LOCKSTEP=host:port[/period_s])");
    }
    if (!(config.lockstep_period_s > 0.0))
      return R::fail(Error::kInvalidArgument, "lockstep: period must be > 0");
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
  impl_->timers[id] =
      Impl::Timer{now() + std::max(0.0, delay_s), 0.0, std::make_shared<Task>(std::move(fn))};
  return id;
}

TimerId EventLoop::call_every(double period_s, Task fn) {
  assert_in_loop_thread();
  const TimerId id = impl_->next_timer_id++;
  period_s = std::max(period_s, 1e-6);
  impl_->timers[id] =
      Impl::Timer{now() + period_s, period_s, std::make_shared<Task>(std::move(fn))};
  return id;
}

bool EventLoop::cancel(TimerId id) {
  assert_in_loop_thread();
  return impl_->timers.erase(id) > 0;
}

Result<void> EventLoop::watch_fd(int fd, std::uint32_t events,
                                 std::function<void(std::uint32_t)> fn) {
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
  impl_->watches[fd] =
      Impl::Watch{events, std::make_shared<std::function<void(std::uint32_t)>>(std::move(fn))};
  return {};
}

Result<void> EventLoop::modify_fd(int fd, std::uint32_t events) {
  assert_in_loop_thread();
  auto it = impl_->watches.find(fd);
  if (it == impl_->watches.end())
    return Result<void>::fail(Error::kInvalidArgument, "modify_fd: not watched");
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
      return Result<void>::fail(Error::kConnectionLost,
                                "lockstep clock lost: " + impl_->dead_reason);
    }
    impl_->iterate(true, deadline);
  }
  return {};
}

Result<void> EventLoop::run_until(const std::function<bool()>& pred, double timeout_s,
                                  const std::string& what) {
  assert_in_loop_thread();
  if (pred()) return {};
  const double start = now();
  const double deadline = start + std::max(0.0, timeout_s);
  for (;;) {
    if (is_lockstep() && !impl_->alive) {
      return Result<void>::fail(Error::kConnectionLost, "lockstep clock lost while waiting for " +
                                                            what + ": " + impl_->dead_reason);
    }
    impl_->iterate(true, deadline);
    // lockstep: the caller resumes at a tick (the simulation held), never between two, so what it
    // does next happens at a defined sim time; data that arrived in between is in the caches by
    // then
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
    (void)run_until([this] { return impl_->tick_outstanding || !impl_->alive; }, kInf,
                    "the next tick");
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
               "uavsim client: EventLoop used from thread %s, not from its loop thread (use "
               "EventLoop::post)\n",
               os.str().c_str());
  std::abort();
}

}  // namespace uavsim::client
