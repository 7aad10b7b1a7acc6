// EventLoop::Impl: the loop's state, shared by the files that implement it. Library internal (not
// installed): only the loop's own sources include it; the library's modules reach the loop through
// LoopServices.
//   event_loop.cpp      the reactor (epoll, timers, posted tasks) and the public EventLoop API
//   lockstep_clock.cpp  the lockstep clock: joining the simulator, ticks, `done`, pipelining
//   loop_config.cpp     LoopConfig (and UAVSIM_LOCKSTEP)
//   loop_services.cpp   LoopServices
#pragma once

#include <sys/epoll.h>

#include <atomic>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <thread>
#include <unordered_map>
#include <vector>

#include "loop_services.hpp"
#include "sim_channel.hpp"
#include "uavsim/client/event_loop.hpp"

namespace uavsim::client {

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
  std::vector<std::uint8_t> done_record;  // a binary done's payload (reused)
  // from the server's replies to `done`: does it wait for the MAVLink seqs named there
  // (api::SeqWaiter)?
  std::optional<bool> mavlink_seq_checked;
  std::map<std::uint64_t, SeqSource> seq_sources;
  std::uint64_t next_seq_source = 1;
  // pipelined lockstep (EventLoop::set_lockstep_pipelined): `done` of the current tick already
  // sent; outputs held until the next tick (requests on the lockstep connection in the SimChannel,
  // each Vehicle link's MAVLink in its own buffer, sent by its flusher)
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
  // Handles what is ready, runs posted tasks and due timers; under lockstep answers the tick when
  // nothing is left to do at this time. With may_block, then waits for something to happen (at most
  // until wake_at on the loop clock, if finite). Returns false when nothing happened.
  bool iterate(bool may_block, double wake_at);
  bool dispatch(int timeout_ms);
  bool run_posted();
  bool run_due_timers();
  void arm_timerfd(double wake_at);
  void on_api_readable();
  // a read of the lockstep connection: a close or an error loses the clock
  void after_read(SimChannel::ReadResult r, const std::string& why);
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
  // a tick from the server (a tick message, or a tick record's): its work may run
  void on_tick(std::int64_t n, double time_s);
  void send_done();
  // done in its binary form on the request ring, or as a line (on TCP, or for vehicles named by
  // name); seqs: (vehicle key, last MAVLink seq sent)
  bool send_done_record(const std::vector<std::pair<std::string, int>>& seqs,
                        std::optional<double> busy_until);
  bool send_done_line(const std::vector<std::pair<std::string, int>>& seqs,
                      std::optional<double> busy_until);
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

}  // namespace uavsim::client
