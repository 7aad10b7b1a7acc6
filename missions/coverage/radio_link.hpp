// The agent program's radio, as the flock sees it: broadcast a frame, take the frames heard. One
// small interface so that the program does not depend on how the radio is reached (the simulator's
// radio on the lockstep connection today, a radio driver on a real drone).
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "radio_messages.hpp"

namespace uavsim::client {
class EventLoop;
}

namespace uavsim::missions::coverage {

class RadioLink {
 public:
  virtual ~RadioLink() = default;
  // Puts a frame (1 to max_frame_bytes() bytes) on air to every agent in range; false if the
  // radio refused it.
  virtual bool broadcast(const Frame& frame) = 0;
  // The largest frame the radio carries (bytes; 127 for 802.15.4 without a MAC header, fewer
  // with one).
  virtual size_t max_frame_bytes() const = 0;
  // The frames heard since the last call, in order of arrival.
  virtual std::vector<Frame> take_received() = 0;
  // Frames refused by the radio so far (queue full, ...).
  virtual unsigned long refused() const = 0;
};

// The simulator's radio of vehicle `index` (uavsim::client::A2aRadio on the loop's lockstep
// connection: frames are seen at the first tick at or after their arrival, in every run alike).
// Nothing, with the reason in *error, when the loop is not on the lockstep clock or the simulator
// refuses the subscription.
std::unique_ptr<RadioLink> open_sim_radio(client::EventLoop& loop, int index, std::string* error);

}  // namespace uavsim::missions::coverage
