#include "detection_drawing.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace uavsim::missions::mbzirc2017 {

namespace {

// BGR; chosen to stand out on sand, the grey deck and the marker's black and white
cv::Scalar colour_of(FrameOutcome::Kind kind) {
  switch (kind) {
    case FrameOutcome::Kind::kAccepted:
      return {0, 220, 0};
    case FrameOutcome::Kind::kRejected:
      return {0, 140, 255};
    case FrameOutcome::Kind::kOffTheDeck:
    case FrameOutcome::Kind::kNoMarker:
      break;
  }
  return {0, 0, 255};
}

}  // namespace

vision::VideoLogFrame detection_log_frame(const cv::Mat& image, double stamp_s,
                                          const FrameOutcome& outcome,
                                          const DrawingContext& context) {
  vision::VideoLogFrame frame;
  frame.stamp_us = static_cast<int64_t>(std::llround(stamp_s * 1e6));
  frame.image = image;
  if (outcome.detection) {
    const vision::MarkerDetection& d = *outcome.detection;
    const cv::Scalar colour = colour_of(outcome.kind);
    const cv::Point2f c(static_cast<float>(d.centre_px.x), static_cast<float>(d.centre_px.y));
    const float r = static_cast<float>(d.radius_px);
    frame.overlays.push_back(vision::Overlay::circle(c, r + 3.0f, colour, 2.0f));
    const float arm = std::max(6.0f, 0.3f * r);
    frame.overlays.push_back(
        vision::Overlay::line(c - cv::Point2f(arm, 0), c + cv::Point2f(arm, 0), colour, 2.0f));
    frame.overlays.push_back(
        vision::Overlay::line(c - cv::Point2f(0, arm), c + cv::Point2f(0, arm), colour, 2.0f));
    char label[64];
    if (outcome.deck_enu_m) {
      std::snprintf(label, sizeof(label), "%s (%.1f, %.1f)", frame_outcome_name(outcome.kind),
                    outcome.deck_enu_m->x(), outcome.deck_enu_m->y());
    } else {
      std::snprintf(label, sizeof(label), "%s", frame_outcome_name(outcome.kind));
    }
    frame.overlays.push_back(
        vision::Overlay::label(c + cv::Point2f(r + 6.0f, -4.0f), label, colour, 0.45f));
  }
  // the caption: the log's per-frame text, also burnt in at the top left for the exported video
  char caption[192];
  const int n = std::snprintf(caption, sizeof(caption), "%s t=%.2f %s, %s, %d detections",
                              context.vehicle.c_str(), stamp_s, context.fsm_state.c_str(),
                              frame_outcome_name(outcome.kind), context.detections);
  std::string text(caption,
                   static_cast<size_t>(std::clamp(n, 0, static_cast<int>(sizeof(caption)) - 1)));
  if (context.truck.initialised) {
    char est[96];
    std::snprintf(est, sizeof(est), "; truck (%.1f, %.1f) at %.1f m/s",
                  context.truck.position_enu_m.x(), context.truck.position_enu_m.y(),
                  context.truck.velocity_enu_m_s.norm());
    text += est;
  }
  frame.text = text;
  frame.overlays.push_back(vision::Overlay::label({6.0f, 16.0f}, text, {255, 255, 255}, 0.4f));
  return frame;
}

}  // namespace uavsim::missions::mbzirc2017
