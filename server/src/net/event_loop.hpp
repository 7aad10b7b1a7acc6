// One reactor thread for the server's sockets, the network I/O thread (muduo's EventLoop; not the
// simulation's loop thread): level-triggered epoll, an eventfd to wake it from other threads, and
// calls run on it on request. The MAVLink endpoints and the sim API's line server register their
// descriptors with the same loop (docs/architecture.md, "Network I/O").
//
// Threads: handlers, wakers' callbacks and ticks run on the I/O thread. Registration (watch,
// change, unwatch) is I/O thread only, or before start(); from elsewhere wrap it in call().
#pragma once

#include <sys/epoll.h>

#include <atomic>
#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <thread>
#include <unordered_map>
#include <vector>

namespace uavsim::server::net {

class EventLoop;

// A coalescing wake-up of one component on the loop: wake() from any thread makes the loop call the
// component's callback once, however many wake() calls came before the loop got to it. Output
// queued before wake() is seen by that callback.
class Waker {
 public:
  // Thread-safe; never blocks (at most one eventfd write per loop pass).
  void wake();

 private:
  friend class EventLoop;
  Waker(EventLoop& loop, std::function<void()> fn) : loop_(loop), fn_(std::move(fn)) {}
  EventLoop& loop_;
  std::function<void()> fn_;
  std::atomic<bool> pending_{false};
};

class EventLoop {
 public:
  // called with the epoll event bits (EPOLLIN, EPOLLOUT, EPOLLERR, ...) of a watched descriptor
  using Handler = std::function<void(std::uint32_t events)>;

  // Creates the epoll set and the wake eventfd. Throws std::runtime_error if the kernel refuses.
  EventLoop();
  // Stops the thread (see stop()) and closes the loop's own descriptors, not the watched ones.
  ~EventLoop();
  EventLoop(const EventLoop&) = delete;
  EventLoop& operator=(const EventLoop&) = delete;

  // Starts the I/O thread. Call once.
  void start();
  // Stops and joins the I/O thread; the handlers are not called afterwards. Thread-safe, not from
  // the I/O thread. Idempotent.
  void stop();

  // Watches fd for events (EPOLLIN, EPOLLOUT, ...), level-triggered: handler runs on the I/O
  // thread while they hold. The loop does not own fd. I/O thread or before start().
  void watch(int fd, std::uint32_t events, Handler handler);
  // Changes the events fd is watched for. I/O thread or before start().
  void change(int fd, std::uint32_t events);
  // Stops watching fd (call before closing it): a ready event of this pass for it is skipped, even
  // if the number is reused by a new descriptor meanwhile. I/O thread or before start().
  void unwatch(int fd);

  // A waker for a component: fn runs on the I/O thread after wake(). The waker lives as long as
  // the loop; a component that goes first must make fn a no-op. I/O thread or before start().
  Waker& make_waker(std::function<void()> fn);
  // Makes a waker's callback a no-op (its component is going; the Waker itself stays valid for
  // wake() calls that race the owner's teardown). I/O thread or before start().
  void disable(Waker& waker) { waker.fn_ = nullptr; }
  // fn runs on the I/O thread after every wait, whether events came or the wait timed out (every
  // kTickMs at most): for deadlines that need no precision (an overload grace period). Returns an
  // id for remove_tick. I/O thread or before start().
  std::size_t add_tick(std::function<void()> fn);
  void remove_tick(std::size_t id) { ticks_.at(id) = nullptr; }

  // Runs fn on the I/O thread and returns when it has run, after the callbacks of every wake()
  // made before the call: on this thread if the I/O thread is not running or this is it.
  // Thread-safe; the caller must not hold a lock that a handler of the loop waits for.
  void call(const std::function<void()>& fn);

  // True on the I/O thread. Thread-safe.
  bool in_io_thread() const { return std::this_thread::get_id() == loop_thread_id_.load(); }

  static constexpr int kTickMs = 200;

 private:
  friend class Waker;
  struct Entry {
    std::uint32_t generation = 0;
    std::shared_ptr<Handler> handler;  // shared: a handler may unwatch its own descriptor
  };
  void run();
  void signal();  // one eventfd write, unless one is pending
  void on_wake();
  void run_calls(std::vector<std::pair<std::uint64_t, std::function<void()>>>& calls);

  int epoll_fd_ = -1;
  int wake_fd_ = -1;
  std::atomic<bool> signalled_{false};  // an eventfd write the loop has not drained yet
  std::atomic<bool> stop_{false};
  std::thread thread_;
  std::atomic<std::thread::id> loop_thread_id_{};
  std::unordered_map<int, Entry> entries_;  // by fd; I/O thread
  std::uint32_t next_generation_ = 1;
  std::vector<std::unique_ptr<Waker>> wakers_;  // I/O thread
  std::vector<std::function<void()>> ticks_;    // I/O thread
  // call(): functions waiting to run on the I/O thread, and how many have run
  std::mutex calls_mutex_;
  std::condition_variable calls_cv_;
  std::vector<std::pair<std::uint64_t, std::function<void()>>> calls_;  // guarded by calls_mutex_
  std::uint64_t calls_queued_ = 0;                                      // guarded by calls_mutex_
  std::uint64_t calls_done_ = 0;                                        // guarded by calls_mutex_
  bool running_ = false;  // the I/O thread runs calls; guarded by calls_mutex_
};

}  // namespace uavsim::server::net
