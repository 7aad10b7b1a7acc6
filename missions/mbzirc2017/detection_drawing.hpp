// The MBZIRC 2017 UAV's video log (--video-log): each processed camera frame with what the vision
// saw drawn on it, so a person can replay a run's landing from the UAV's own eyes
// (uavsim-videolog-export makes an MP4 of it). Pure: a frame and its outcome in, a video-log frame
// out.
#pragma once

#include <string>

#include "truck_perception.hpp"
#include "uavsim/vision/video_log.hpp"

namespace uavsim::missions::mbzirc2017 {

// What the FSM knew when the frame was processed, for the frame's caption.
struct DrawingContext {
  std::string vehicle;    // the UAV's name
  std::string fsm_state;  // landing_state_name() of the FSM's state
  int detections = 0;     // accepted so far
  TruckKnowledge truck;   // the filter's estimate (initialised or not)
};

// The frame (grey or BGR) with: the detected ring (green when the filter took it, orange when its
// gate refused it, red when its ray missed the deck), a cross on its centre, the deck position it
// gave, and a caption with the time, the FSM state and the filter's truck estimate. The image is
// shared, not copied (the log stores it without the drawings).
vision::VideoLogFrame detection_log_frame(const cv::Mat& image, double stamp_s,
                                          const FrameOutcome& outcome,
                                          const DrawingContext& context);

}  // namespace uavsim::missions::mbzirc2017
