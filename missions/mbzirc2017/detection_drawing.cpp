#include "detection_drawing.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <opencv2/imgproc.hpp>

namespace uavsim::missions::mbzirc2017 {

namespace {

constexpr double kLabelScale = 0.35;  // Hershey simplex: about 7 px a character, 9 px capitals

// BGR; chosen to stand out on sand, the grey deck and the marker's black and white
cv::Scalar colour_of(FrameOutcome::Kind kind) {
  switch (kind) {
    case FrameOutcome::Kind::kAccepted:
      return {0, 220, 0};
    case FrameOutcome::Kind::kRejected:
      return {0, 140, 255};
    case FrameOutcome::Kind::kOffTheDeck:
    case FrameOutcome::Kind::kSettling:
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
    // under the ring (above it near the bottom edge), kept inside the image: the camera's frames
    // are small (384 x 168 on the 2017 hexa)
    int baseline = 0;
    const cv::Size size =
        cv::getTextSize(label, cv::FONT_HERSHEY_SIMPLEX, kLabelScale, 1, &baseline);
    const float below = c.y + r + 6.0f + static_cast<float>(size.height);
    const float y = below < static_cast<float>(image.rows - 2) ? below : c.y - r - 6.0f;
    const float x = std::clamp(c.x - 0.5f * static_cast<float>(size.width), 2.0f,
                               std::max(2.0f, static_cast<float>(image.cols - size.width - 2)));
    frame.overlays.push_back(vision::Overlay::label({x, y}, label, colour, kLabelScale));
  }
  // the caption, the log's per-frame text (the exporter burns it in at the top left): short lines,
  // to fit the camera's small frames
  char caption[192];
  std::snprintf(caption, sizeof(caption), "%s t=%.2f %s\n%s, %d detections",
                context.vehicle.c_str(), stamp_s, context.fsm_state.c_str(),
                frame_outcome_name(outcome.kind), context.detections);
  frame.text = caption;
  if (context.truck.initialised) {
    char est[96];
    std::snprintf(est, sizeof(est), "\ntruck (%.1f, %.1f) %.1f m/s",
                  context.truck.position_enu_m.x(), context.truck.position_enu_m.y(),
                  context.truck.velocity_enu_m_s.norm());
    frame.text += est;
  }
  return frame;
}

}  // namespace uavsim::missions::mbzirc2017
