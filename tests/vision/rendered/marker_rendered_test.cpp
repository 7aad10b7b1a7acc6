// Landing-marker detector and the truck's Kalman filter on frames rendered from
// models/worlds/mbzirc2017.xml (issue 7): the truck drives its eight (Simulation + Truck object),
// the hexa's down-looking camera (640 x 480, fovy 60 deg) hangs 10 m above the deck, rigidly on a
// vehicle tilted by up to 10 deg; the marker's arena position comes from the frame's pose and
// intrinsics and the deck height, and is scored against the truck's ground truth.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <deque>
#include <random>
#include <utility>
#include <vector>

#include "rendered_fixture.hpp"
#include "uavsim/common/angles.hpp"
#include "uavsim/vision/eight_track.hpp"
#include "uavsim/vision/marker_detector.hpp"
#include "uavsim/vision/track_kalman.hpp"

namespace uavsim::vision::rendered {
namespace {

constexpr double kMaxMarkerErrorM = 0.3;  // arena coordinates, horizontal
constexpr double kMinMarkerDetectionRate = 0.95;
constexpr double kHeightAboveDeckM = 10.0;
constexpr double kMaxTiltRad = 10.0 * common::kPi / 180.0;
constexpr int kWidthPx = 640;
constexpr int kHeightPx = 480;
// the hexa's camera mount (mbzirc2017.xml: uavsim:gimbal:uav0_gimbal "uav0 down 0 0 -0.09")
const Eigen::Vector3d kMountBodyM(0.0, 0.0, -0.09);

constexpr double kFrameRateHz = 7.0;
constexpr double kLatencyS = 0.150;
constexpr double kMaxTrackErrorM = 1.0;
constexpr double kTrackRunS = 62.0;  // one lap (61 s at 15 km/h) and a little
constexpr double kSettleS = 1.0;     // after the filter starts, errors count

int64_t to_us(double t_s) { return static_cast<int64_t>(std::llround(t_s * 1e6)); }

// The hexa hovering over a point with a body-fixed down camera (the tilt reaches the camera: no
// gimbal cancels it). Puts the vehicle and the camera's body; render() forwards.
void place_hexa(RenderedWorld& w, const Eigen::Vector3d& camera_enu_m, double roll_rad,
                double pitch_rad, double yaw_rad) {
  const Eigen::Quaterniond q_body = q_enu_body_from_rpy(roll_rad, pitch_rad, yaw_rad);
  server::physics::set_vehicle_state(w.world(), 0, camera_enu_m - q_body * kMountBodyM, q_body,
                                     Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero());
  w.place_camera("uav0_gimbal", camera_enu_m, q_body * look(0.0, -common::kPi / 2));
}

// Runs the simulation to t_s (the truck drives) and puts the truck where it is at exactly t_s, the
// frame's stamp: a physics step leaves mocap bodies where they were before it.
void drive_to(RenderedWorld& w, double t_s) {
  w.sim->run_until(t_s);
  w.objects.trucks.at(0)->before_step(*w.sim);
}

TEST(MarkerRendered, LocatesMarkerOnTheDrivingTruckFrom10mWithTilt) {
  // each pose at 640 x 480 and at 320 x 240 (ring radius ~32 and ~16 px), every other pose with
  // shadows (the cab's may fall on the deck; shadow acne greys the thin marker's paint)
  struct Look {
    const char* name;
    int width_px;
    int height_px;
    bool shadows;
    double min_detection_rate;
    int frames = 0;
    int detected = 0;
    double worst_m = 0.0;
    double sum_m = 0.0;
  };
  // 320 x 240 with shadows: the ring is 3 px wide and shadow acne (the marker is a 1 mm box on
  // the deck, models/objects/truck.xml) speckles all of it in some poses; seen, not required
  constexpr double kMinRateWithAcneAt320 = 0.8;
  Look looks[] = {{"640x480", 640, 480, false, kMinMarkerDetectionRate},
                  {"640x480 shadows", 640, 480, true, kMinMarkerDetectionRate},
                  {"320x240", 320, 240, false, kMinMarkerDetectionRate},
                  {"320x240 shadows", 320, 240, true, kMinRateWithAcneAt320}};
  std::vector<server::render::CameraConfig> cameras;
  for (const Look& l : looks) {
    cameras.push_back(camera("uav0_down", l.width_px, l.height_px));
    cameras.back().flags.shadows = l.shadows;
  }
  RenderedWorld w("mbzirc2017.xml", 1, cameras);
  const server::objects::Truck& truck = *w.objects.trucks.at(0);
  MarkerDetector detector;
  std::mt19937_64 rng(2017);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);

  // a lap: straights, both circles, the crossing
  constexpr int kPoses = 80;
  for (int i = 0; i < kPoses; ++i) {
    drive_to(w, 0.5 + 0.75 * i);
    const server::objects::TruckState truth = truck.state(w.sim->time_s());
    // the camera up to 2.5 m off the deck centre sideways, any heading, tilted up to 10 deg
    const Eigen::Vector3d camera_enu_m =
        truth.deck_centre_enu_m +
        Eigen::Vector3d(2.5 * unit(rng), 2.5 * unit(rng), kHeightAboveDeckM);
    place_hexa(w, camera_enu_m, kMaxTiltRad * unit(rng), kMaxTiltRad * unit(rng),
               common::kPi * unit(rng));
    for (int size = 0; size < 2; ++size) {
      const int index = 2 * size + i % 2;
      Look& l = looks[index];
      const server::render::CameraFrame f = w.render(index);
      ASSERT_EQ(f.stamp_us, to_us(w.sim->time_s()));
      ++l.frames;
      const auto d = detector.detect(to_bgr(f));
      if (!d) continue;
      const auto p = marker_position_enu(*d, f.intrinsics, to_pose(f),
                                         truth.deck_centre_enu_m.z());
      ASSERT_TRUE(p.has_value());
      ++l.detected;
      const double error_m = (p->head<2>() - truth.deck_centre_enu_m.head<2>()).norm();
      l.worst_m = std::max(l.worst_m, error_m);
      l.sum_m += error_m;
      EXPECT_LT(error_m, kMaxMarkerErrorM) << "frame " << i << " (" << l.name << ")";
    }
  }
  for (const Look& l : looks) {
    std::printf("marker %-16s detected %d/%d, error mean %.3f m worst %.3f m\n", l.name, l.detected,
                l.frames, l.sum_m / std::max(l.detected, 1), l.worst_m);
    EXPECT_EQ(l.frames, kPoses / 2);
    EXPECT_GE(static_cast<double>(l.detected) / l.frames, l.min_detection_rate) << l.name;
    EXPECT_LT(l.worst_m, kMaxMarkerErrorM) << l.name;
  }
}

TEST(TrackKalmanRendered, TracksTheDrivingTruckAt7HzWith150msLatency) {
  RenderedWorld w("mbzirc2017.xml", 1, {camera("uav0_down", kWidthPx, kHeightPx)});
  const server::objects::Truck& truck = *w.objects.trucks.at(0);
  const PinholeIntrinsics k = w.renderer->intrinsics(0);
  MarkerDetector detector;
  // the vision library's eight, from the world's numbers (uavsim:truck:track = 20 45 0 0 0)
  const server::objects::EightTrackParams& tp = truck.params().track;
  EightTrackParams params;
  params.circle_radius_m = tp.circle_radius_m;
  params.centre_separation_m = tp.centre_separation_m;
  params.centre_enu_m = tp.centre_enu_m;
  params.yaw_rad = tp.yaw_rad;
  const EightTrack track(params);
  TrackKalman filter(track);

  // a follower 10 m above the deck that lags the truck by 0.4 s and rocks up to 10 deg as it
  // chases it; images at 7 Hz, each result delivered 150 ms after its image, stamped with the
  // image's sim time; the estimate at "now" is scored at every image and every delivery
  struct Pending {
    double deliver_s;
    int64_t stamp_us;
    Eigen::Vector2d position_enu_m;
  };
  std::deque<Pending> pending;
  const double start_s = 1.0;
  int frames = 0, detections = 0, rejected = 0, scored = 0;
  double first_scored_s = -1.0, last_scored_s = 0.0, worst_m = 0.0, sum_sq = 0.0;
  std::optional<double> initialised_s;
  const auto score = [&](double now_s) {
    if (!initialised_s || now_s < *initialised_s + kSettleS) return;
    const auto e = filter.estimate_at(to_us(now_s));
    ASSERT_TRUE(e.has_value());
    const double error_m = (e->position_enu_m - truck.state(now_s).position_enu_m.head<2>()).norm();
    EXPECT_LT(error_m, kMaxTrackErrorM) << "t = " << now_s;
    worst_m = std::max(worst_m, error_m);
    sum_sq += error_m * error_m;
    ++scored;
    if (first_scored_s < 0.0) first_scored_s = now_s;
    last_scored_s = now_s;
  };
  for (int i = 0;; ++i) {
    const double image_s = start_s + i / kFrameRateHz;
    // deliver what finished before this image
    while (!pending.empty() && pending.front().deliver_s <= image_s) {
      const Pending p = pending.front();
      pending.pop_front();
      w.sim->run_until(p.deliver_s);
      const MeasurementResult r = filter.add_measurement(p.stamp_us, p.position_enu_m);
      if (r == MeasurementResult::kRejected || r == MeasurementResult::kRestarted) ++rejected;
      if (filter.initialised() && !initialised_s) initialised_s = w.sim->time_s();
      score(w.sim->time_s());
    }
    if (image_s > start_s + kTrackRunS) break;

    drive_to(w, image_s);
    const double now_s = w.sim->time_s();
    const Eigen::Vector3d lagged = truck.state(std::max(0.0, now_s - 0.4)).deck_centre_enu_m;
    place_hexa(w, lagged + Eigen::Vector3d(0.0, 0.0, kHeightAboveDeckM),
               kMaxTiltRad * std::sin(2.0 * common::kPi * now_s / 7.0),
               kMaxTiltRad * std::cos(2.0 * common::kPi * now_s / 11.0),
               truck.state(now_s).yaw_rad);
    const server::render::CameraFrame f = w.render(0);
    ++frames;
    score(now_s);
    const auto d = detector.detect(to_bgr(f));
    if (!d) continue;
    const auto p = marker_position_enu(*d, k, to_pose(f), truck.state(now_s).deck_centre_enu_m.z());
    if (!p) continue;
    ++detections;
    pending.push_back({now_s + kLatencyS, f.stamp_us, p->head<2>()});
  }
  const double rms_m = std::sqrt(sum_sq / std::max(scored, 1));
  std::printf(
      "kalman: %d images, %d detections, %d rejected, %d scores over %.1f s: "
      "error rms %.3f m worst %.3f m\n",
      frames, detections, rejected, scored, last_scored_s - first_scored_s, rms_m, worst_m);
  EXPECT_GE(last_scored_s - first_scored_s, 60.0);
  EXPECT_GE(detections, 0.95 * frames);
  EXPECT_EQ(rejected, 0);
  EXPECT_LT(worst_m, kMaxTrackErrorM);
}

}  // namespace
}  // namespace uavsim::vision::rendered
