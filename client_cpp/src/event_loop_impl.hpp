// EventLoop internals shared with the rest of the library (vehicle links register their MAVLink sequence
// numbers here for the lockstep `done`). Not installed, not part of the API.
#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <unordered_map>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>
#include <sys/epoll.h>

#include "api_stream.hpp"
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
  // a vehicle link: () -> (vehicle key for `done`, last seq sent) or nullopt when it has sent nothing yet
  using SeqSource = std::function<std::optional<std::pair<std::string, int>>()>;

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

  // lockstep
  int api_fd = -1;
  ApiStream api_stream;
  // camera frames arriving on the lockstep connection, by camera name (camera.cpp)
  using FrameSink = std::function<void(const nlohmann::json& header, std::string_view bytes)>;
  std::map<std::string, FrameSink> frame_sinks;
  // other events on the lockstep connection (e.g. "sensor": onboard switches, switches.cpp), by event
  // name; each handler sees every such event and picks its own
  using EventSink = std::function<void(const nlohmann::json& event)>;
  std::multimap<std::string, std::pair<std::uint64_t, EventSink>> event_sinks;
  std::uint64_t next_event_sink = 1;
  // replies to requests sent with api_request(), by id
  std::map<std::string, std::function<void(const nlohmann::json&)>> reply_handlers;
  std::uint64_t next_request_id = 1;
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
  // outputs held until the next tick (requests on the lockstep connection here, each Vehicle link's
  // MAVLink in its own buffer, sent by its flusher)
  bool pipelined = false;
  bool done_sent = false;
  bool outputs_held = false;
  // ... and the lockstep connection is not read past the tick until the tick's work is done (the
  // next tick may already be on its way: the simulation did not wait)
  bool api_held = false;
  std::string held_api;
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
  void handle_api_message(const nlohmann::json& j, std::string_view payload);
  // Sends a request on the lockstep connection; on_reply gets the whole reply. False if there is none.
  bool api_request(nlohmann::json request, std::function<void(const nlohmann::json&)> on_reply);
  void send_done();
  // pipelined lockstep, at a tick: sends the outputs held since the last tick ...
  void release_held_outputs();
  // ... then answers `done` before the tick's work, and holds what the work sends
  void answer_early();
  // pipelined lockstep: stops / resumes reading the lockstep connection (see api_held)
  void hold_api();
  void resume_api();
  std::uint32_t api_interest() const { return api_held ? 0u : (EPOLLIN | EPOLLRDHUP); }
  void update_api_interest();  // epfd's interest in api_fd := api_interest()
  void lose_clock(const std::string& why);
  bool send_api(const std::string& line);

  std::uint64_t add_seq_source(SeqSource s) {
    seq_sources[next_seq_source] = std::move(s);
    return next_seq_source++;
  }
  void remove_seq_source(std::uint64_t id) { seq_sources.erase(id); }
  // A link that holds its own output while outputs_held registers how to send it.
  std::uint64_t add_output_flusher(std::function<void()> f) {
    output_flushers[next_output_flusher] = std::move(f);
    return next_output_flusher++;
  }
  void remove_output_flusher(std::uint64_t id) { output_flushers.erase(id); }
};

}  // namespace uavsim::client
