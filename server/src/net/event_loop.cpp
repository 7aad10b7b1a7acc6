#include "net/event_loop.hpp"

#include <sys/eventfd.h>
#include <unistd.h>

#include <cerrno>
#include <stdexcept>

namespace uavsim::server::net {

namespace {

// epoll tags: 0 is the wake eventfd; a watched descriptor is (generation << 32) | fd, so an event
// of a descriptor unwatched earlier in the same pass never reaches the handler of its number's next
// owner
constexpr std::uint64_t kWakeTag = 0;

std::uint64_t tag_of(int fd, std::uint32_t generation) {
  return (std::uint64_t{generation} << 32) | static_cast<std::uint32_t>(fd);
}

}  // namespace

void Waker::wake() {
  // the loop clears pending_ before it calls fn_: a wake() that finds it set is covered by that
  // call
  if (pending_.exchange(true)) return;
  loop_.signal();
}

EventLoop::EventLoop() {
  epoll_fd_ = epoll_create1(EPOLL_CLOEXEC);
  wake_fd_ = eventfd(0, EFD_NONBLOCK | EFD_CLOEXEC);
  if (epoll_fd_ < 0 || wake_fd_ < 0) {
    if (epoll_fd_ >= 0) close(epoll_fd_);
    if (wake_fd_ >= 0) close(wake_fd_);
    throw std::runtime_error("event loop: epoll_create1/eventfd failed");
  }
  epoll_event ev{};
  ev.events = EPOLLIN;
  ev.data.u64 = kWakeTag;
  epoll_ctl(epoll_fd_, EPOLL_CTL_ADD, wake_fd_, &ev);
}

EventLoop::~EventLoop() {
  stop();
  close(epoll_fd_);
  close(wake_fd_);
}

void EventLoop::start() {
  {
    std::lock_guard lock(calls_mutex_);
    running_ = true;
  }
  thread_ = std::thread([this] { run(); });
}

void EventLoop::stop() {
  stop_.store(true);
  // a direct write: signalled_ may be set by a wake-up the loop will never drain
  const std::uint64_t one = 1;
  [[maybe_unused]] const auto n = write(wake_fd_, &one, sizeof(one));
  if (thread_.joinable()) thread_.join();
}

void EventLoop::watch(int fd, std::uint32_t events, Handler handler) {
  Entry& e = entries_[fd];
  e.generation = next_generation_++;
  e.handler = std::make_shared<Handler>(std::move(handler));
  epoll_event ev{};
  ev.events = events;
  ev.data.u64 = tag_of(fd, e.generation);
  epoll_ctl(epoll_fd_, EPOLL_CTL_ADD, fd, &ev);
}

void EventLoop::change(int fd, std::uint32_t events) {
  auto it = entries_.find(fd);
  if (it == entries_.end()) return;
  epoll_event ev{};
  ev.events = events;
  ev.data.u64 = tag_of(fd, it->second.generation);
  epoll_ctl(epoll_fd_, EPOLL_CTL_MOD, fd, &ev);
}

void EventLoop::unwatch(int fd) {
  if (entries_.erase(fd) == 0) return;
  epoll_ctl(epoll_fd_, EPOLL_CTL_DEL, fd, nullptr);
}

Waker& EventLoop::make_waker(std::function<void()> fn) {
  wakers_.push_back(std::unique_ptr<Waker>(new Waker(*this, std::move(fn))));
  return *wakers_.back();
}

std::size_t EventLoop::add_tick(std::function<void()> fn) {
  ticks_.push_back(std::move(fn));
  return ticks_.size() - 1;
}

void EventLoop::call(const std::function<void()>& fn) {
  std::unique_lock lock(calls_mutex_);
  if (!running_ || in_io_thread()) {
    lock.unlock();
    fn();
    return;
  }
  const std::uint64_t ticket = ++calls_queued_;
  calls_.emplace_back(ticket, fn);
  lock.unlock();
  signal();
  lock.lock();
  calls_cv_.wait(lock, [&] { return calls_done_ >= ticket; });
}

void EventLoop::signal() {
  if (signalled_.exchange(true)) return;  // one eventfd write until the loop drains it
  const std::uint64_t one = 1;
  [[maybe_unused]] const auto n = write(wake_fd_, &one, sizeof(one));
}

void EventLoop::on_wake() {
  std::uint64_t count = 0;
  [[maybe_unused]] const auto r = read(wake_fd_, &count, sizeof(count));
  // cleared before the wakers are looked at (see Waker::wake and signal)
  signalled_.store(false);
  // the calls queued so far run after the wakers: a call() returns after every wake() that came
  // before it was queued has been served
  std::vector<std::pair<std::uint64_t, std::function<void()>>> calls;
  {
    std::lock_guard lock(calls_mutex_);
    calls.swap(calls_);
  }
  for (auto& w : wakers_) {
    if (w->pending_.exchange(false) && w->fn_) w->fn_();
  }
  run_calls(calls);
}

void EventLoop::run_calls(std::vector<std::pair<std::uint64_t, std::function<void()>>>& calls) {
  if (calls.empty()) return;
  for (auto& [ticket, fn] : calls) fn();
  {
    std::lock_guard lock(calls_mutex_);
    calls_done_ = calls.back().first;
  }
  calls_cv_.notify_all();
}

void EventLoop::run() {
  loop_thread_id_.store(std::this_thread::get_id());
  std::vector<epoll_event> events(256);
  while (!stop_.load()) {
    const int n = epoll_wait(epoll_fd_, events.data(), static_cast<int>(events.size()), kTickMs);
    if (n < 0 && errno != EINTR) break;
    for (int k = 0; k < n && !stop_.load(std::memory_order_relaxed); ++k) {
      const std::uint64_t tag = events[k].data.u64;
      if (tag == kWakeTag) {
        on_wake();
        continue;
      }
      auto it = entries_.find(static_cast<int>(tag & 0xffffffffu));
      if (it == entries_.end() || it->second.generation != static_cast<std::uint32_t>(tag >> 32))
        continue;
      const std::shared_ptr<Handler> handler = it->second.handler;
      (*handler)(events[k].events);
    }
    for (auto& tick : ticks_) {
      if (tick) tick();
    }
  }
  // callers of call() waiting now would wait for ever: run theirs here, later ones run inline
  std::vector<std::pair<std::uint64_t, std::function<void()>>> left;
  {
    std::lock_guard lock(calls_mutex_);
    running_ = false;
    left.swap(calls_);
  }
  run_calls(left);
  loop_thread_id_.store(std::thread::id());
}

}  // namespace uavsim::server::net
