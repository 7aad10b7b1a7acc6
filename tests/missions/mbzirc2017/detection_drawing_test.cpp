// The MBZIRC 2017 UAV's video log drawings (detection_drawing.hpp): a synthetic frame of the marker
// on the truck's track, seen from 8 m by the mission's own camera pose, goes through
// TruckPerception; the log frame must ring the marker where it is in the image, in the colour of
// what the filter did with it, and caption the FSM state; a frame of bare sand carries only the
// caption.
#include "detection_drawing.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <opencv2/imgproc.hpp>

#include "uavsim/common/angles.hpp"
#include "uavsim/vision/synthetic_scene.hpp"

namespace uavsim::missions::mbzirc2017 {
namespace {

constexpr double kAltitudeM = 8.0;
constexpr double kRingRadiusRelTol = 0.25;

vision::PinholeIntrinsics down_camera() {
  return vision::PinholeIntrinsics::from_fovy(640, 480, common::kPi / 3);
}

const vision::Overlay* first_of(const vision::VideoLogFrame& f, vision::Overlay::Kind kind) {
  for (const vision::Overlay& o : f.overlays) {
    if (o.kind == kind) return &o;
  }
  return nullptr;
}

TEST(DetectionDrawing, RingsTheAcceptedMarkerWhereItIsAndCaptionsTheState) {
  const MissionConfig config;
  TruckPerception perception(config);
  const auto k = down_camera();
  // the marker on the track, the UAV 1.5 m beside it (off the image centre)
  const vision::EightTrack track(config.track);
  const Eigen::Vector2d marker = track.point_enu(10.0);
  const Eigen::Vector3d uav(marker.x() + 1.5, marker.y() - 1.0, kAltitudeM);
  const vision::CameraPose pose = perception.camera_pose(uav, 0.3);
  cv::Mat image = vision::synthetic::sand_background(k, 7);
  vision::synthetic::render_marker(k, pose, vision::LandingMarkerGeometry{}, marker, 0.2,
                                   config.deck_height_m, &image);
  cv::Mat grey;
  cv::cvtColor(image, grey, cv::COLOR_BGR2GRAY);
  const auto seen = perception.on_frame(grey, k, 1'000'000, pose);
  ASSERT_TRUE(seen.has_value());
  const FrameOutcome& outcome = perception.last_outcome();
  ASSERT_EQ(outcome.kind, FrameOutcome::Kind::kAccepted);

  DrawingContext context;
  context.vehicle = "uav0";
  context.fsm_state = "Search";
  context.detections = perception.detections();
  const vision::VideoLogFrame f = detection_log_frame(grey, 1.0, outcome, context);
  EXPECT_EQ(f.stamp_us, 1'000'000);
  EXPECT_EQ(f.image.data, grey.data);  // shared, the drawings stay separate
  const vision::Overlay* ring = first_of(f, vision::Overlay::Kind::kCircle);
  ASSERT_NE(ring, nullptr);
  // where the marker's centre projects: the ray through the ring's centre meets the deck at the
  // marker
  const auto hit = vision::pixel_to_plane_enu(
      k, pose, Eigen::Vector2d(ring->geometry_px[0], ring->geometry_px[1]), config.deck_height_m);
  ASSERT_TRUE(hit.has_value());
  EXPECT_LT((hit->head<2>() - marker).norm(), 0.2);
  // the marker's 0.65 m ring radius at 6.5 m is about 0.65 / 6.5 * f pixels; drawn 3 px outside it
  const double expect_px = 0.65 / (kAltitudeM - config.deck_height_m) * k.fx_px + 3.0;
  EXPECT_NEAR(ring->geometry_px[2], expect_px, kRingRadiusRelTol * expect_px);
  EXPECT_EQ(ring->colour_bgr, cv::Scalar(0, 220, 0));  // accepted: green
  EXPECT_NE(f.text.find("uav0 t=1.00 Search\naccepted, 1 detections"), std::string::npos) << f.text;
}

TEST(DetectionDrawing, AFrameWithoutTheMarkerCarriesOnlyItsText) {
  const MissionConfig config;
  TruckPerception perception(config);
  const auto k = down_camera();
  const vision::CameraPose pose = perception.camera_pose({0, 0, kAltitudeM}, 0.0);
  cv::Mat grey;
  cv::cvtColor(vision::synthetic::sand_background(k, 3), grey, cv::COLOR_BGR2GRAY);
  EXPECT_FALSE(perception.on_frame(grey, k, 500'000, pose).has_value());
  EXPECT_EQ(perception.last_outcome().kind, FrameOutcome::Kind::kNoMarker);
  DrawingContext context;
  context.vehicle = "uav0";
  context.fsm_state = "Centre";
  const vision::VideoLogFrame f =
      detection_log_frame(grey, 0.5, perception.last_outcome(), context);
  EXPECT_EQ(first_of(f, vision::Overlay::Kind::kCircle), nullptr);
  EXPECT_TRUE(f.overlays.empty());
  EXPECT_NE(f.text.find("no marker"), std::string::npos) << f.text;
}

TEST(DetectionDrawing, ARejectedSightingIsDrawnOrangeWithItsDeckPosition) {
  FrameOutcome outcome;
  outcome.kind = FrameOutcome::Kind::kRejected;
  vision::MarkerDetection d;
  d.centre_px = {100, 120};
  d.radius_px = 30;
  outcome.detection = d;
  outcome.deck_enu_m = Eigen::Vector2d(12.3, -4.5);
  const vision::VideoLogFrame f =
      detection_log_frame(cv::Mat(480, 640, CV_8UC1, cv::Scalar(90)), 2.0, outcome, {});
  const vision::Overlay* ring = first_of(f, vision::Overlay::Kind::kCircle);
  ASSERT_NE(ring, nullptr);
  EXPECT_EQ(ring->colour_bgr, cv::Scalar(0, 140, 255));
  EXPECT_FLOAT_EQ(ring->geometry_px[0], 100.0f);
  EXPECT_FLOAT_EQ(ring->geometry_px[1], 120.0f);
  bool labelled = false;
  for (const vision::Overlay& o : f.overlays) labelled |= o.text == "rejected (12.3, -4.5)";
  EXPECT_TRUE(labelled);
}

}  // namespace
}  // namespace uavsim::missions::mbzirc2017
