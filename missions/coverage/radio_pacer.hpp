// An agent's radio sends one frame at a time (802.15.4: 250 kbit/s, 4.256 ms for a full 127-byte
// frame). Frames handed to it faster than that wait in its queue, and a beacon queued behind them
// goes out late while the receivers take it as news. An aggregation message over a fragmented map
// runs to tens of fragments (108 for 5 quads over 600 x 600 m), and every agent sent a copy of its
// own every 0.5 s whether the last one had gone out or not: during a deploy, followers steered by
// the leader's position 2-3 s old while its record looked fresh, fell behind it and bunched up
// along the line until pairs collided (25 quads, --gcs, p = 0.003, seed 3: 17 crashed). So an
// agent's beacons go straight to the radio and its aggregation frames through this pacer: a share
// of the airtime, with a short burst allowed after a pause; and the next copy is taken only once
// the last one has gone out (the retransmission period stretches to the message's airtime). Pure:
// the caller passes its step.
#pragma once

#include <cstddef>
#include <deque>
#include <vector>

#include "radio_messages.hpp"

namespace uavsim::missions::coverage {

// Time on air of a frame at 250 kbit/s with the 6-byte PHY header (preamble, delimiter, length).
double frame_airtime_s(size_t frame_bytes);

class RadioPacer {
 public:
  // share: of the radio's airtime, for the paced frames (0, 1]; the rest is the beacons' margin.
  // burst_s: the airtime that may go out at once after a pause (a short message is not delayed;
  // a beacon waits at most about this long behind the paced frames), at least the airtime of one
  // frame of max_frame_bytes (the largest it is given), or a long pause would never earn one.
  RadioPacer(double share, double burst_s, size_t max_frame_bytes = kMaxFrameBytes);

  // Nothing left to send: the next message may be queued.
  bool idle() const { return queue_.empty(); }
  // Queues a message's frames, sent in order by take().
  void push(std::vector<Frame> frames);
  // The frames whose airtime fits what the share of the steps so far has earned (dt_s: the time
  // since the last call), earned also while idle, up to burst_s.
  std::vector<Frame> take(double dt_s);

 private:
  double share_;
  double burst_s_;
  std::deque<Frame> queue_;
  double credit_s_ = 0.0;
};

}  // namespace uavsim::missions::coverage
