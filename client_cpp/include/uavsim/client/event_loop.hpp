// The event loop every mission program runs on (seed 6.1): epoll over file descriptors, timers and tasks
// posted from other threads, all dispatched on one thread, the loop thread.
//
// Its clock is chosen by configuration alone (seed 6.5), so mission code is the same on a real drone and in
// the simulator:
//   * host clock (default): the host's steady clock; timers are a timerfd.
//   * lockstep clock (LoopConfig::lockstep, or the environment variable UAVSIM_LOCKSTEP=host:port[/period_s]):
//     the loop joins the simulator's lockstep (docs/protocol.md "Lockstep contract") and now() is sim time.
//     At each tick it handles what has arrived, runs the timers due at the tick's time, and then answers
//     `done` with the last MAVLink sequence number each vehicle link sent, so commands sent during the tick
//     take effect at that tick. The simulation does not advance while the loop is working on a tick.
//   * pipelined lockstep (set_lockstep_pipelined): the same clock, with a fixed one-tick compute
//     latency, like an onboard computer whose outputs go out one period after the data they were
//     computed from. At tick n the loop sends what the program produced during tick n-1 (MAVLink of
//     every Vehicle link, requests on the lockstep connection), answers `done` at once, and then runs
//     the program's work for tick n while the simulation steps on to tick n+1. Runs stay
//     deterministic (what the program sees at tick n and when its outputs take effect do not depend
//     on timing) and the simulator and the program use the CPU at the same time. Descriptors the
//     program writes itself (its own UDP sockets) are not held back: their timing is the host's.
//
// Waiting: run_for() / run_until() keep dispatching events (and answering ticks) while they wait, so mission
// code can be written as straight-line code. Blocking calls of Vehicle are built on them.
//
// Detached timing (seed 6.5): run_busy(d, fn) runs CPU-heavy work that appears to take exactly d seconds of
// sim time under lockstep without holding the simulation back; on the host clock it just runs fn.
//
// Thread contract: everything except post(), stop() and in_loop_thread() is for the loop thread only (the
// thread that created the loop); assert_in_loop_thread() aborts with a message when that is violated.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <string>

#include "uavsim/client/result.hpp"

namespace uavsim::client {

struct LoopConfig {
  enum class Clock { kHost, kLockstep };
  Clock clock = Clock::kHost;
  // lockstep only: where the simulator's socket API listens, and the tick period (rounded by the server to
  // whole control steps); timers fire at the first tick at or after their deadline
  std::string lockstep_host = "127.0.0.1";
  int lockstep_port = 5700;
  double lockstep_period_s = 0.01;
  // wall seconds the server may take to answer the join or to send the next tick before the loop gives up
  double lockstep_wall_timeout_s = 60.0;
  // lockstep only: how the simulator's messages reach the loop. kAuto: through shared memory when
  // the server is on this machine and offers it (docs/protocol.md, "Shared-memory stream"), else
  // TCP; kTcp: always TCP (UAVSIM_API_TRANSPORT=tcp); kShm: the shared memory or a failure to
  // create the loop (UAVSIM_API_TRANSPORT=shm). Missions are the same on either; the two for
  // comparisons and tests.
  enum class Transport { kAuto, kTcp, kShm };
  Transport lockstep_transport = Transport::kAuto;

  // The host clock, unless UAVSIM_LOCKSTEP=host:port[/period_s] is set (e.g.
  // "127.0.0.1:5700/0.02"); UAVSIM_API_TRANSPORT=tcp or shm sets lockstep_transport to kTcp or
  // kShm.
  static LoopConfig from_env();
  static LoopConfig host();
  static LoopConfig lockstep(const std::string& host, int port, double period_s = 0.01);
};

using TimerId = std::uint64_t;
using Task = std::function<void()>;

class EventLoop {
 public:
  // Creates a loop on the calling thread (which becomes its loop thread). Under lockstep this connects to
  // the simulator and joins; kConnectionRefused / kTimeout / kProtocol when that fails.
  static Result<std::unique_ptr<EventLoop>> create(const LoopConfig& config = LoopConfig::from_env());
  ~EventLoop();
  EventLoop(const EventLoop&) = delete;
  EventLoop& operator=(const EventLoop&) = delete;

  // Seconds on the loop's clock: host: since the loop was created; lockstep: sim time of the current tick.
  double now() const;
  bool is_lockstep() const;
  // False once the lockstep connection is lost (the clock then stops: waits fail with kConnectionLost).
  bool clock_alive() const;

  // Timers (loop clock). fn runs on the loop thread. call_every's first call is one period from now.
  TimerId call_after(double delay_s, Task fn);
  TimerId call_every(double period_s, Task fn);
  bool cancel(TimerId id);  // false if it already fired (one-shot) or never existed

  // File descriptors (level-triggered). events: kReadable | kWritable; fn(events that happened,
  // incl. kError). Under lockstep a descriptor is reported readable only as a tick arrives, before
  // the clock moves to it: what arrived while the simulation ran up to the tick is handled at the
  // previous tick's time, in every run alike (and what arrives while a tick is being worked on
  // waits for the next). Writability and errors are reported at once.
  static constexpr std::uint32_t kReadable = 1, kWritable = 2, kError = 4;
  Result<void> watch_fd(int fd, std::uint32_t events, std::function<void(std::uint32_t)> fn);
  Result<void> modify_fd(int fd, std::uint32_t events);
  void unwatch_fd(int fd);

  // Thread-safe: runs fn on the loop thread soon (at the current tick under lockstep).
  void post(Task fn);

  // Dispatches until stop() (thread-safe) is called; tasks posted before stop() still run.
  void run();
  void stop();
  // Dispatches for duration_s of loop time. kConnectionLost if the lockstep clock dies.
  Result<void> run_for(double duration_s);
  // Dispatches until pred() holds (checked after every dispatch), at most timeout_s of loop time:
  // kTimeout with `what` in the message when it does not.
  Result<void> run_until(const std::function<bool()>& pred, double timeout_s, const std::string& what = "condition");

  // Detached timing: runs fn (no I/O on loop-owned descriptors inside it) as if it took duration_s.
  // Lockstep: the current tick is answered with busy_until = now + duration_s, fn runs while the simulation
  // carries on, and the call returns at the first tick at or after that time (waiting for fn if it is slower:
  // the simulation then waits for it). Host clock: runs fn and returns.
  void run_busy(double duration_s, const std::function<void()>& fn);

  // Pipelined lockstep (see the header comment), from the next tick on; off by default, nothing on
  // the host clock. Turn it on once the program's links are connected: a connection opened while
  // the simulation runs ahead is accepted at a timing-dependent sim time. While on, run_busy()
  // does not detach (every tick is answered).
  void set_lockstep_pipelined(bool on);
  bool lockstep_pipelined() const;

  bool in_loop_thread() const;
  void assert_in_loop_thread() const;  // aborts naming the caller's thread when not on the loop thread

 private:
  struct Impl;
  // the library's modules (Vehicle, CameraSubscriber, A2aRadio, PadSwitches) reach the loop's
  // simulator connection and its lockstep `done` through this narrow internal interface only
  friend class LoopServices;
  explicit EventLoop(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace uavsim::client
