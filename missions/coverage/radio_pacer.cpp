#include "radio_pacer.hpp"

#include <algorithm>
#include <cmath>

namespace uavsim::missions::coverage {

namespace {
constexpr double kBitRate_bit_s = 250000.0;  // 802.15.4, 2.4 GHz O-QPSK PHY
constexpr size_t kPhyHeaderBytes = 6;  // preamble (4), start-of-frame delimiter (1), length (1)
}  // namespace

double frame_airtime_s(size_t frame_bytes) {
  return static_cast<double>(frame_bytes + kPhyHeaderBytes) * 8.0 / kBitRate_bit_s;
}

RadioPacer::RadioPacer(double share, double burst_s, size_t max_frame_bytes)
    : share_(std::clamp(share, 0.01, 1.0)),
      // at least one full frame, or a long pause would never earn enough for one
      burst_s_(std::max(std::isfinite(burst_s) ? burst_s : 0.0,
                        frame_airtime_s(std::min(max_frame_bytes, kMaxAggregateFrameBytes)))),
      credit_s_(burst_s_) {}

void RadioPacer::push(std::vector<Frame> frames) {
  for (Frame& f : frames) queue_.push_back(std::move(f));
}

std::vector<Frame> RadioPacer::take(double dt_s) {
  if (std::isfinite(dt_s) && dt_s > 0.0) credit_s_ = std::min(credit_s_ + dt_s * share_, burst_s_);
  std::vector<Frame> out;
  while (!queue_.empty() && credit_s_ >= frame_airtime_s(queue_.front().size())) {
    credit_s_ -= frame_airtime_s(queue_.front().size());
    out.push_back(std::move(queue_.front()));
    queue_.pop_front();
  }
  return out;
}

}  // namespace uavsim::missions::coverage
