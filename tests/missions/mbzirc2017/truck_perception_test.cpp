// The truck's track across a step of the UAV's own position estimate (truck_perception.hpp, issue
// 36's seed 172). Synthetic frames of the marker driving along the eight, each rendered from the
// UAV's true pose but placed by its estimate: before the step the estimate is right, after it 2 m
// off to the left. The track made before the step must not be used after it: set aside (only its
// velocity), frames taken while the estimate settles unused, and the new track made from frames
// taken once it has settled, in the estimate's new frame, so that the UAV's relative estimate is
// right again.
#include "truck_perception.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <opencv2/imgproc.hpp>

#include "uavsim/common/angles.hpp"
#include "uavsim/vision/synthetic_scene.hpp"

namespace uavsim::missions::mbzirc2017 {
namespace {

constexpr double kAltitudeM = 5.0;
constexpr double kTruckSpeedMS = 15.0 / 3.6;
constexpr double kStartArcM = 10.0;  // on the straight part of the eight's first lobe
// placement noise of one sighting is centimetres (detector, 640 px); the filter's two-point start
// and extrapolation add a little
constexpr double kPositionToleranceM = 0.3;
constexpr double kVelocityToleranceMS = 0.5;

class TrackAcrossAStep : public ::testing::Test {
 protected:
  TrackAcrossAStep() : perception(config), track(config.track) {}

  Eigen::Vector2d marker_at(double t_s) const {
    return track.point_enu(kStartArcM + kTruckSpeedMS * t_s);
  }
  // one frame at t_s: the UAV 0.5 m behind and 0.3 m beside the marker, its estimate off by
  // estimate_error_m; the outcome's kind
  FrameOutcome::Kind frame(double t_s) {
    const Eigen::Vector2d m = marker_at(t_s);
    const Eigen::Vector3d truth(m.x() - 0.5, m.y() + 0.3, kAltitudeM);
    const Eigen::Vector3d estimate =
        truth + Eigen::Vector3d(estimate_error_m.x(), estimate_error_m.y(), 0.0);
    const vision::PinholeIntrinsics k =
        vision::PinholeIntrinsics::from_fovy(640, 480, common::kPi / 3);
    cv::Mat image = vision::synthetic::sand_background(k, 11);
    vision::synthetic::render_marker(k, perception.camera_pose(truth, 0.0),
                                     vision::LandingMarkerGeometry{}, m, 0.0, config.deck_height_m,
                                     &image);
    cv::Mat grey;
    cv::cvtColor(image, grey, cv::COLOR_BGR2GRAY);
    (void)perception.on_frame(grey, k, static_cast<int64_t>(std::llround(t_s * 1e6)),
                              perception.camera_pose(estimate, 0.0));
    return perception.last_outcome().kind;
  }
  TruckKnowledge knowledge(double t_s) const {
    return perception.knowledge(t_s, Eigen::Vector2d::Zero());
  }

  MissionConfig config;
  TruckPerception perception;
  vision::EightTrack track;
  Eigen::Vector2d estimate_error_m = Eigen::Vector2d::Zero();
};

TEST_F(TrackAcrossAStep, PreStepTrackServesOnlyItsVelocityUntilANewOneIsMadeAfterSettling) {
  // the track before the step: right
  for (double t : {0.0, 0.5, 1.0}) ASSERT_EQ(frame(t), FrameOutcome::Kind::kAccepted);
  const TruckKnowledge before = knowledge(1.0);
  ASSERT_TRUE(before.initialised);
  EXPECT_FALSE(before.position_stale);
  EXPECT_LT((before.position_enu_m - marker_at(1.0)).norm(), kPositionToleranceM);

  // the step (2 m to the left in the estimate): the old track is set aside, its velocity serves
  estimate_error_m = Eigen::Vector2d(0.0, 2.0);
  perception.on_estimate_step();
  EXPECT_TRUE(perception.rebuilding());
  const TruckKnowledge stale = knowledge(1.2);
  ASSERT_TRUE(stale.initialised);
  EXPECT_TRUE(stale.position_stale);
  const Eigen::Vector2d truck_velocity =
      kTruckSpeedMS * track.tangent_enu(kStartArcM + kTruckSpeedMS * 1.2);
  EXPECT_LT((stale.velocity_enu_m_s - truck_velocity).norm(), kVelocityToleranceMS);
  // no sighting since the step: nothing fresh to descend on
  EXPECT_LT(stale.last_seen_s, 0.0);

  // frames while the estimate settles are not used
  EXPECT_EQ(frame(1.5), FrameOutcome::Kind::kSettling);
  EXPECT_EQ(frame(2.0), FrameOutcome::Kind::kSettling);
  EXPECT_TRUE(knowledge(2.0).position_stale);
  EXPECT_LT(knowledge(2.0).last_seen_s, 0.0);

  // settled: a new track from the frames taken from then on, in the estimate's new frame
  perception.on_estimate_settled(2.2);
  EXPECT_EQ(frame(2.2), FrameOutcome::Kind::kAccepted);
  EXPECT_TRUE(knowledge(2.2).position_stale);  // one point does not start a track
  EXPECT_EQ(frame(2.7), FrameOutcome::Kind::kAccepted);
  EXPECT_FALSE(perception.rebuilding());
  const TruckKnowledge after = knowledge(2.7);
  ASSERT_TRUE(after.initialised);
  EXPECT_FALSE(after.position_stale);
  EXPECT_DOUBLE_EQ(after.last_seen_s, 2.7);
  // where the estimate's new frame has the marker (the truth plus the step), not where the old
  // track would have it: the UAV's position relative to it is right again
  const Eigen::Vector2d marker_in_new_frame = marker_at(2.7) + estimate_error_m;
  EXPECT_LT((after.position_enu_m - marker_in_new_frame).norm(), kPositionToleranceM);
  EXPECT_GT((after.position_enu_m - marker_at(2.7)).norm(), 2.0 - kPositionToleranceM);
}

// A second step while the new track is being made: what it took since the first is in yet another
// frame, so it starts over, and the oldest track's velocity still serves meanwhile.
TEST_F(TrackAcrossAStep, ASecondStepBeforeTheNewTrackStartedStartsItOver) {
  for (double t : {0.0, 0.5, 1.0}) ASSERT_EQ(frame(t), FrameOutcome::Kind::kAccepted);
  estimate_error_m = Eigen::Vector2d(0.0, 2.0);
  perception.on_estimate_step();
  perception.on_estimate_settled(1.5);
  EXPECT_EQ(frame(1.5), FrameOutcome::Kind::kAccepted);
  estimate_error_m = Eigen::Vector2d(1.5, 2.0);
  perception.on_estimate_step();
  EXPECT_EQ(frame(2.0), FrameOutcome::Kind::kSettling);
  const TruckKnowledge k = knowledge(2.0);
  ASSERT_TRUE(k.initialised);
  EXPECT_TRUE(k.position_stale);
  perception.on_estimate_settled(2.5);
  EXPECT_EQ(frame(2.5), FrameOutcome::Kind::kAccepted);
  EXPECT_EQ(frame(3.0), FrameOutcome::Kind::kAccepted);
  const TruckKnowledge after = knowledge(3.0);
  EXPECT_FALSE(after.position_stale);
  EXPECT_LT((after.position_enu_m - (marker_at(3.0) + estimate_error_m)).norm(),
            kPositionToleranceM);
}

}  // namespace
}  // namespace uavsim::missions::mbzirc2017
