// LoopServices: the loop's internals the library's modules may use (loop_services.hpp).
#include "loop_services.hpp"

#include "event_loop_impl.hpp"

namespace uavsim::client {

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
