// Balloon detector on frames rendered from models/worlds/mbzirc2020.xml (issue 7): uav0's forward
// camera (640 x 480, fovy 22 deg as the world has it) placed around the seeded balloons at 3 to
// 25 m, from below (sky behind the balloon) and from above (ground behind it), with the balloon
// anywhere in the frame, other poles and balloons behind, and uav1 beside or behind it. Ground
// truth: the balloons' centres from the BalloonField, visibility by ray casting into the world.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

#include "rendered_fixture.hpp"
#include "uavsim/common/angles.hpp"
#include "uavsim/vision/balloon_detector.hpp"

namespace uavsim::vision::rendered {
namespace {

constexpr double kMinDetectionRate = 0.95;  // of balloons >= 20 px wide, whole and unoccluded
constexpr double kMinRequiredWidthPx = 20.0;
constexpr double kMaxRangeError = 0.10;  // relative, 3 to 25 m
constexpr double kMinRangeM = 3.0;
constexpr double kMaxRangeM = 25.0;
constexpr double kMatchRadiusShare =
    0.3;  // a detection within 0.3 r (at least 3 px) is that balloon
constexpr double kMatchMinPx = 3.0;
constexpr int kWidthPx = 640;
constexpr int kHeightPx = 480;
constexpr int kBalloons = 5;  // in mbzirc2020.xml

// what the world says about one balloon in one frame
struct BalloonTruth {
  Eigen::Vector2d centre_px = Eigen::Vector2d::Zero();
  double width_px = 0.0;
  double range_m = 0.0;
  bool in_front = false;
  bool whole = false;       // the disc lies inside the frame
  bool unoccluded = false;  // centre and rim rays meet the balloon first
};

// projects a balloon and casts rays at its centre and rim (0.9 R around the disc facing the camera)
BalloonTruth balloon_truth(RenderedWorld& w, const server::render::CameraFrame& f,
                           const server::objects::BalloonState& b, int geom_id, int pole_id) {
  BalloonTruth t;
  const PinholeIntrinsics k = f.intrinsics;
  const Eigen::Vector3d p_cam = to_pose(f).enu_to_cam(b.position_enu_m);
  t.range_m = p_cam.norm();
  t.in_front = p_cam.z() > b.radius_m;
  if (!t.in_front) return t;
  t.centre_px = k.project(p_cam);
  // the sphere's outline subtends sin(a) = R / d about its centre ray
  const double radius_px = k.fx_px * std::tan(std::asin(b.radius_m / t.range_m));
  t.width_px = 2.0 * radius_px;
  constexpr double kMarginPx = 2.0;
  t.whole = t.centre_px.x() - radius_px >= kMarginPx && t.centre_px.y() - radius_px >= kMarginPx &&
            t.centre_px.x() + radius_px <= k.width_px - 1 - kMarginPx &&
            t.centre_px.y() + radius_px <= k.height_px - 1 - kMarginPx;
  const Eigen::Vector3d view = (b.position_enu_m - f.position_enu_m).normalized();
  const Eigen::Vector3d e1 = view.cross(Eigen::Vector3d::UnitZ()).normalized();
  const Eigen::Vector3d e2 = view.cross(e1);
  // (the balloon's own pole may hide a sliver of its bottom: that is how it looks)
  t.unoccluded = w.first_hit(f.position_enu_m, b.position_enu_m) == geom_id;
  for (int i = 0; i < 8 && t.unoccluded; ++i) {
    const double a = 2.0 * common::kPi * i / 8;
    const Eigen::Vector3d rim =
        b.position_enu_m + 0.9 * b.radius_m * (std::cos(a) * e1 + std::sin(a) * e2);
    const int hit = w.first_hit(f.position_enu_m, rim);
    t.unoccluded = hit == geom_id || hit == pole_id;
  }
  return t;
}

bool matches(const BalloonDetection& d, const BalloonTruth& t) {
  const double tol_px = std::max(kMatchMinPx, kMatchRadiusShare * 0.5 * t.width_px);
  return t.in_front &&
         (Eigen::Vector2d(d.centre_px.x, d.centre_px.y) - t.centre_px).norm() <= tol_px;
}

// places uav0 level under its camera (mount 0.09 m ahead, 0.04 m below the body origin), as the
// forward gimbal would carry it; its cutter bar and blades may show
void place_uav0_with_camera(RenderedWorld& w, const Eigen::Vector3d& camera_enu_m, double yaw_rad,
                            double pitch_rad) {
  const Eigen::Quaterniond q_body(Eigen::AngleAxisd(yaw_rad, Eigen::Vector3d::UnitZ()));
  server::physics::set_vehicle_state(w.world(), 0,
                                     camera_enu_m - q_body * Eigen::Vector3d(0.09, 0.0, -0.04),
                                     q_body, Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero());
  w.place_camera("uav0_gimbal", camera_enu_m, look(yaw_rad, pitch_rad));
}

struct SweepStats {
  int required = 0;
  int detected = 0;
  int ranged = 0;
  int false_positives = 0;
  double worst_range_error = 0.0;
  double sum_range_error = 0.0;
};

TEST(BalloonRendered, DetectsAndRangesBalloonsFrom3To25m) {
  // the same camera twice: MuJoCo's defaults as the server renders (no sky, no shadows), and with
  // the sky box and the sun's shadows on
  server::render::CameraConfig sky_and_shadows = camera("uav0_front", kWidthPx, kHeightPx);
  sky_and_shadows.flags.skybox = true;
  sky_and_shadows.flags.shadows = true;
  RenderedWorld w("mbzirc2020.xml", 1,
                  {camera("uav0_front", kWidthPx, kHeightPx), sky_and_shadows});
  const PinholeIntrinsics k = w.renderer->intrinsics(0);
  BalloonDetector detector({}, k);
  std::vector<int> geoms, poles;
  for (int i = 0; i < kBalloons; ++i) {
    geoms.push_back(w.geom(balloon_part(i, "balloon")));
    poles.push_back(w.geom(balloon_part(i, "pole")));
  }

  // sky: camera 0.8 to 2.2 m above the ground, looking up at the balloon (black without the sky
  // box, blue with it); ground: 5 to 35 deg above it, looking down (shadows on every other frame)
  enum Background { kBlackSky, kSkyBox, kGround, kBackgrounds };
  const double distances_m[] = {3.0, 4.0, 5.5, 7.5, 10.0, 13.0, 17.0, 21.0, 25.0};
  SweepStats all, by_background[kBackgrounds], with_quad;
  for (const uint64_t seed : {1u, 2u, 3u}) {
    w.sim->reset(seed);
    const auto& balloons = w.objects.balloons->balloons();
    ASSERT_EQ(static_cast<int>(balloons.size()), kBalloons);
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    int frame = 0;
    for (int target = 0; target < kBalloons; ++target) {
      const Eigen::Vector3d c = balloons[target].position_enu_m;
      for (const double d : distances_m) {
        for (int bg = kBlackSky; bg < kBackgrounds; ++bg, ++frame) {
          // a camera position d from the balloon, clear of the other balloons and poles
          Eigen::Vector3d cam;
          for (int attempt = 0; attempt < 50; ++attempt) {
            const double az = 2.0 * common::kPi * unit(rng);
            const double el = bg != kGround ? std::asin((0.8 + 1.4 * unit(rng) - c.z()) / d)
                                            : (5.0 + 30.0 * unit(rng)) * common::kPi / 180.0;
            cam = c + d * Eigen::Vector3d(std::cos(el) * std::cos(az), std::cos(el) * std::sin(az),
                                          std::sin(el));
            bool clear = true;
            for (const auto& o : balloons) {
              clear = clear && (o.position_enu_m - cam).norm() > 1.5 &&
                      (o.position_enu_m - cam).head<2>().norm() > 0.5;
            }
            if (clear) break;
          }
          // aim so that the balloon lands anywhere in the frame with its whole disc inside
          const Eigen::Vector3d to_c = c - cam;
          const double yaw0 = std::atan2(to_c.y(), to_c.x());
          const double pitch0 = std::atan2(to_c.z(), to_c.head<2>().norm());
          const double r_px = k.fx_px * std::tan(std::asin(0.3 / d));
          const double du = (2.0 * unit(rng) - 1.0) * 0.9 * (0.5 * kWidthPx - 1.15 * r_px - 6.0);
          const double dv = (2.0 * unit(rng) - 1.0) * 0.9 * (0.5 * kHeightPx - 1.15 * r_px - 6.0);
          const double yaw = yaw0 + std::atan(du / k.fx_px);
          const double pitch = pitch0 + std::atan(dv / k.fy_px);
          place_uav0_with_camera(w, cam, yaw, pitch);

          // every third frame: uav1 in view, beside the balloon nearer the camera, or behind it
          const bool quad_in_view = frame % 3 == 0;
          Eigen::Vector3d uav1(10.0, -27.0, 0.0);  // its start, out of view
          if (quad_in_view) {
            const Eigen::Vector3d left = Eigen::Vector3d::UnitZ().cross(to_c).normalized();
            const bool behind = frame % 2 == 0;
            const double along = behind ? d + 3.0 : std::max(2.0, 0.6 * d);
            // beside: clear of the balloon's outline (0.3 m at d) by the quad's half span and more;
            // behind: its centre 0.25 m off the balloon's at the balloon's scale, half hidden
            const double side_m = behind ? 0.25 * along / d : 0.3 * along / d + 0.6;
            uav1 = cam + along * to_c.normalized() + (du > 0 ? -side_m : side_m) * left;
          }
          server::physics::set_vehicle_state(w.world(), 1, uav1, Eigen::Quaterniond::Identity(),
                                             Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero());

          const bool shadows = bg == kSkyBox || (bg == kGround && frame % 2 == 1);
          const server::render::CameraFrame f = w.render(shadows ? 1 : 0);
          const std::vector<BalloonDetection> detections = detector.detect(to_bgr(f));

          std::vector<BalloonTruth> truths;
          for (int i = 0; i < kBalloons; ++i)
            truths.push_back(balloon_truth(w, f, balloons[i], geoms[i], poles[i]));
          for (const auto& det : detections) {
            const bool known = std::any_of(truths.begin(), truths.end(),
                                           [&](const BalloonTruth& t) { return matches(det, t); });
            if (known) continue;
            for (SweepStats* s : {&all, &by_background[bg]}) ++s->false_positives;
            ADD_FAILURE() << "seed " << seed << " frame " << frame << ": detection at ("
                          << det.centre_px.x << ", " << det.centre_px.y << ") r " << det.radius_px
                          << " px is no balloon";
          }
          for (const BalloonTruth& t : truths) {
            if (!t.whole || !t.unoccluded || t.width_px < kMinRequiredWidthPx) continue;
            std::vector<SweepStats*> stats = {&all, &by_background[bg]};
            if (quad_in_view) stats.push_back(&with_quad);
            for (SweepStats* s : stats) ++s->required;
            const auto hit =
                std::find_if(detections.begin(), detections.end(),
                             [&](const BalloonDetection& det) { return matches(det, t); });
            if (hit == detections.end()) continue;
            const double error = std::abs(hit->range_m - t.range_m) / t.range_m;
            for (SweepStats* s : stats) {
              ++s->detected;
              if (t.range_m < kMinRangeM || t.range_m > kMaxRangeM) continue;
              ++s->ranged;
              s->sum_range_error += error;
              s->worst_range_error = std::max(s->worst_range_error, error);
            }
            if (t.range_m >= kMinRangeM && t.range_m <= kMaxRangeM) {
              EXPECT_LT(error, kMaxRangeError)
                  << "seed " << seed << " frame " << frame << " range " << t.range_m;
            }
          }
        }
      }
    }
  }
  const auto report = [](const char* name, const SweepStats& s) {
    std::printf(
        "%-8s required %3d detected %3d (%.1f%%), range error mean %.2f%% worst %.2f%%, "
        "false positives %d\n",
        name, s.required, s.detected, 100.0 * s.detected / std::max(1, s.required),
        100.0 * s.sum_range_error / std::max(1, s.ranged), 100.0 * s.worst_range_error,
        s.false_positives);
  };
  report("all", all);
  report("black", by_background[kBlackSky]);
  report("skybox", by_background[kSkyBox]);
  report("ground", by_background[kGround]);
  report("uav1", with_quad);
  // every distance, background and seed contributes: 3 seeds x 5 balloons x 9 distances x 3
  ASSERT_GE(all.required, 300);
  EXPECT_GE(with_quad.required, 100);
  for (const SweepStats& s :
       {all, by_background[kBlackSky], by_background[kSkyBox], by_background[kGround], with_quad}) {
    EXPECT_GE(static_cast<double>(s.detected) / s.required, kMinDetectionRate);
    EXPECT_LT(s.worst_range_error, kMaxRangeError);
  }
  EXPECT_EQ(all.false_positives, 0);
}

}  // namespace
}  // namespace uavsim::vision::rendered
