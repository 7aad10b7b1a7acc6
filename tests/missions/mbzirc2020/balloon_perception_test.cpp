// The balloon pipeline's camera pose on a synthetic frame of one-UAV field seed 14 at 60.0 s, the
// moment before its crash: braking hard, the gimbal's loop had left the camera 6 deg above the
// commanded level, and the compass read 4.5 deg off. The program has what a drone has: the
// telemetry (GPS position, compass heading) and the gimbal's report of its camera's attitude
// (roll and pitch relative to the horizon, yaw relative to the heading, as uavsim-server's gimbal
// device reports it), never the frame's true pose.
#include "balloon_perception.hpp"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <vector>

#include "mission_config.hpp"
#include "uavsim/common/angles.hpp"
#include "uavsim/common/frames.hpp"
#include "uavsim/vision/camera_model.hpp"
#include "uavsim/vision/synthetic_scene.hpp"

namespace uavsim::missions::mbzirc2020 {
namespace {

namespace frames = common::frames;
using common::kDegToRad;

constexpr double kHeightTol_m = 0.05;
constexpr double kAngleTol_rad = 1e-9;

struct Seed14AtSixtySeconds {
  // ground truth (truth_uav0.csv, summary.json) and the field's errors
  Eigen::Vector3d vehicle_enu_m{35.80, -14.48, 2.83};
  double heading_rad = 34.3 * kDegToRad;
  double camera_elevation_rad = 6.0 * kDegToRad;  // commanded: 0 (level)
  double camera_yaw_rad = 0.0;               // the loop's yaw lag, relative to the heading (ENU)
  Eigen::Vector3d balloon_enu_m{39.86, -12.59, 3.14};
  Eigen::Vector3d gps_bias_m{0.4, 0.3, -0.5};
  double compass_offset_rad = 4.5 * kDegToRad;
  // what the program has: telemetry
  Eigen::Vector3d telemetry_enu_m() const { return vehicle_enu_m + gps_bias_m; }
  double telemetry_yaw_rad() const { return heading_rad + compass_offset_rad; }
  vision::CameraPose true_camera(const MissionConfig& config) const {
    return vision::camera_pose_from_vehicle(
        vehicle_enu_m, vision::q_enu_body_from_rpy(0.0, 0.0, heading_rad),
        vision::GimbalAngles{camera_elevation_rad, camera_yaw_rad, true},
        config.camera_offset_body_m);
  }
  // and the gimbal's report: the true camera's attitude in MAVLink's vehicle frame (NED turned by
  // the true heading: the device measures against gravity and its joint encoders)
  GimbalReport report(const MissionConfig& config, double time_s) const {
    const Eigen::Matrix3d R_enu_mount =
        true_camera(config).R_enu_cam * vision::R_mount_cam().transpose();
    const Eigen::Quaterniond q_ned_cam =
        frames::q_ned_frd_from_q_enu_flu(Eigen::Quaterniond(R_enu_mount));
    const double heading_ned_rad = frames::yaw_ned_from_yaw_enu(heading_rad);
    const frames::Euler e = frames::euler_from_q_ned_frd(
        Eigen::AngleAxisd(-heading_ned_rad, Eigen::Vector3d::UnitZ()) * q_ned_cam);
    return {time_s, e.roll_rad, e.pitch_rad, e.yaw_rad};
  }
};

// The forward camera of models/worlds/mbzirc2020_field.xml (384 x 216, 22 deg vertical).
vision::PinholeIntrinsics front_camera() {
  return vision::PinholeIntrinsics::from_fovy(384, 216, 22.0 * kDegToRad);
}

cv::Mat render(const vision::PinholeIntrinsics& k, const vision::CameraPose& camera,
               const Eigen::Vector3d& balloon_enu_m, double elevation_rad, uint64_t seed) {
  // the horizon sits below the image's centre when the camera looks up
  cv::Mat image =
      vision::synthetic::sky_sand_background(k, k.cy_px + k.fy_px * std::tan(elevation_rad), seed);
  vision::synthetic::render_sphere(k, camera.enu_to_cam(balloon_enu_m), 0.6, {45, 175, 50},
                                   Eigen::Vector3d(0.1, -1.0, -0.3).normalized(), &image);
  vision::synthetic::add_noise(2.0, seed + 1, &image);
  return image;
}

// The balloon's place seen through `pose_of` in four frames at 15 fps (the tracker confirms a
// balloon on its third hit), in the telemetry's frame.
template <typename PoseOf>
std::vector<BalloonSighting> sightings(const Seed14AtSixtySeconds& c, PoseOf pose_of) {
  const MissionConfig config;
  BalloonPerception perception(config);
  perception.set_camera_pitch(0.0, 50.0);  // levelled for the pierce long before
  // the gimbal reports every 20 ms, the frames are exposed in between
  GimbalReports reports;
  for (int i = 0; i < 20; ++i) reports.add(c.report(config, 59.9 + 0.02 * i));
  const vision::PinholeIntrinsics k = front_camera();
  const vision::CameraPose truth = c.true_camera(config);
  for (int i = 0; i < 4; ++i) {
    const double stamp_s = 60.0 + i / 15.0;
    const cv::Mat frame = render(k, truth, c.balloon_enu_m, c.camera_elevation_rad, 14 + 2 * i);
    const std::optional<GimbalReport> report = reports.at(stamp_s, 0.1);
    EXPECT_TRUE(report && report->time_s <= stamp_s && report->time_s > stamp_s - 0.02);
    perception.on_frame(frame, k, stamp_s, pose_of(perception, *report));
  }
  return perception.sightings();
}

// Where the balloon is in the program's own frame: its GPS bias shifts it as it shifts us; the
// compass offset turns it about us (the bearing is read from the compass)
Eigen::Vector3d in_our_frame(const Seed14AtSixtySeconds& c) {
  const Eigen::Vector3d from_us = c.balloon_enu_m - c.vehicle_enu_m;
  return c.telemetry_enu_m() +
         Eigen::AngleAxisd(c.compass_offset_rad, Eigen::Vector3d::UnitZ()) * from_us;
}

TEST(Mbzirc2020BalloonPerception, PlacesTheBalloonWithTheGimbalsReportedAttitude) {
  const Seed14AtSixtySeconds c;
  const auto seen = sightings(c, [&](const BalloonPerception& p, const GimbalReport& reported) {
    return p.camera_pose(c.telemetry_enu_m(), c.telemetry_yaw_rad(), reported);
  });
  ASSERT_EQ(seen.size(), 1u);
  // its height as our own (the pierce's blades go there); where the compass says it is
  EXPECT_NEAR(seen[0].position_enu_m.z(), in_our_frame(c).z(), kHeightTol_m);
  EXPECT_LT((seen[0].position_enu_m - in_our_frame(c)).head<2>().norm(), 0.15);
}

TEST(Mbzirc2020BalloonPerception, TheReportedAttitudeCarriesTheGimbalsYawAndRoll) {
  // the loop's yaw lag too (a turn): 3 deg left of the heading
  Seed14AtSixtySeconds c;
  c.camera_yaw_rad = 3.0 * kDegToRad;
  const auto seen = sightings(c, [&](const BalloonPerception& p, const GimbalReport& reported) {
    return p.camera_pose(c.telemetry_enu_m(), c.telemetry_yaw_rad(), reported);
  });
  ASSERT_EQ(seen.size(), 1u);
  EXPECT_NEAR(seen[0].position_enu_m.z(), in_our_frame(c).z(), kHeightTol_m);
  EXPECT_LT((seen[0].position_enu_m - in_our_frame(c)).head<2>().norm(), 0.15);
  // and the report's angles are the camera's, in MAVLink's signs
  const GimbalReport r = c.report(MissionConfig{}, 60.0);
  EXPECT_NEAR(r.pitch_rad, 6.0 * kDegToRad, kAngleTol_rad);
  EXPECT_NEAR(r.yaw_rad, -3.0 * kDegToRad, kAngleTol_rad);  // clockwise positive
  EXPECT_NEAR(r.roll_rad, 0.0, kAngleTol_rad);
}

TEST(Mbzirc2020BalloonPerception, TheCommandedElevationPutsSeed14sBalloonLow) {
  // the pose the program used before: the commanded gimbal elevation. The same frames place the
  // balloon 0.4 m low (the pierce then flew under it until it left the image's top edge).
  const Seed14AtSixtySeconds c;
  const auto seen = sightings(c, [&](const BalloonPerception& p, const GimbalReport&) {
    return p.camera_pose(c.telemetry_enu_m(), c.telemetry_yaw_rad(), 0.0);
  });
  ASSERT_EQ(seen.size(), 1u);
  EXPECT_LT(seen[0].position_enu_m.z(), in_our_frame(c).z() - 0.3);
}

TEST(Mbzirc2020GimbalReports, AFrameGetsTheLastReportNotAfterItsExposure) {
  GimbalReports reports;
  reports.add({10.00, 0.0, 0.1, 0.0});
  reports.add({10.02, 0.0, 0.2, 0.0});
  reports.add({10.02, 0.0, 0.9, 0.0});  // a repeat: dropped
  reports.add({10.04, 0.0, 0.3, 0.0});
  EXPECT_DOUBLE_EQ(reports.at(10.039, 0.1)->pitch_rad, 0.2);
  EXPECT_DOUBLE_EQ(reports.at(10.04, 0.1)->pitch_rad, 0.3);
  EXPECT_DOUBLE_EQ(reports.at(10.10, 0.1)->pitch_rad, 0.3);
  EXPECT_FALSE(reports.at(9.99, 0.1));   // before the first
  EXPECT_FALSE(reports.at(10.20, 0.1));  // the reports stopped
}

}  // namespace
}  // namespace uavsim::missions::mbzirc2020
