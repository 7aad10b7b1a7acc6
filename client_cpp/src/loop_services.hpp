// LoopServices: what the library's own modules need from an EventLoop beyond its public reactor API,
// and nothing more. EventLoop grants it on purpose (a friend); no module sees the loop's internals.
//
//   * sim_channel(): the lockstep loop's simulator connection (SimChannel): CameraSubscriber, A2aRadio
//     and PadSwitches send their requests and register their sinks there.
//   * the lockstep contract of a MAVLink link (Vehicle, seed 6.5): a sequence source, whose last sent
//     MAVLink seq the loop names in `done`, and an output flusher with outputs_held(), which hold what a
//     link sends during a pipelined tick's work until the next tick.
//
// Library internal (not installed); loop thread only, like the loop.
#pragma once

#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <utility>

#include "uavsim/client/event_loop.hpp"

namespace uavsim::client {

class SimChannel;

class LoopServices {
 public:
  explicit LoopServices(EventLoop& loop) : impl_(*loop.impl_) {}

  // The lockstep connection, or nullptr on the host clock. It stays the same object for the loop's
  // life; once the lockstep clock is lost it is closed (is_open() false).
  SimChannel* sim_channel() const;

  // A vehicle link: () -> (vehicle key for `done`, last MAVLink seq sent), or nullopt when it has sent
  // nothing yet. Registered sources are asked at every `done`.
  using SeqSource = std::function<std::optional<std::pair<std::string, int>>()>;
  std::uint64_t add_seq_source(SeqSource source);
  void remove_seq_source(std::uint64_t id);

  // Pipelined lockstep: true while a tick's work runs; a link then keeps what it sends, and the loop
  // calls its flusher to send it at the next tick (before `done`).
  bool outputs_held() const;
  std::uint64_t add_output_flusher(std::function<void()> flush);
  void remove_output_flusher(std::uint64_t id);

  // The server's answer to `done`: does it wait for the MAVLink seqs named there (api::SeqWaiter)?
  // nullopt until a `done` has been answered, and on the host clock.
  std::optional<bool> mavlink_seq_checked() const;

 private:
  EventLoop::Impl& impl_;
};

}  // namespace uavsim::client
