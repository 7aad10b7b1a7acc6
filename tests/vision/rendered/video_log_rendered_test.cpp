// Video log of rendered frames (issue 7): uav0's forward camera approaches a balloon in
// mbzirc2020.xml; each frame goes into a VLOG with the detector's circle, a range label and a text
// line, and comes back with its stamp, overlays and text intact and an image the detector still
// reads after JPEG compression.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "rendered_fixture.hpp"
#include "uavsim/vision/balloon_detector.hpp"
#include "uavsim/vision/video_log.hpp"

namespace uavsim::vision::rendered {
namespace {

constexpr int kFrames = 12;
constexpr double kCameraRateHz = 15.0;
constexpr double kMinPsnrDb = 30.0;  // JPEG quality 90 on flat-shaded frames
constexpr double kMaxRangeError = 0.10;
// the detection on the decoded frame vs on the rendered one: JPEG ringing moves the rim
constexpr double kCentreTolShare = 0.05;  // of the radius

TEST(VideoLogRendered, LogsRenderedFramesWithOverlaysAndReadsThemBack) {
  RenderedWorld w("mbzirc2020.xml", 1, {camera("uav0_front", 640, 480)});
  const PinholeIntrinsics k = w.renderer->intrinsics(0);
  BalloonDetector detector({}, k);
  const Eigen::Vector3d balloon = w.objects.balloons->balloons().at(0).position_enu_m;

  const std::filesystem::path path =
      std::filesystem::path(::testing::TempDir()) / "vision_rendered_approach.vlog";
  auto writer = VideoLogWriter::open(path);
  ASSERT_TRUE(writer.ok());

  // fly towards the balloon from 20 m to 6 m at 1.4 m per frame, level, 0.5 m below it
  std::vector<VideoLogFrame> written;
  std::vector<BalloonDetection> detected;
  for (int i = 0; i < kFrames; ++i) {
    w.sim->run_until(i / kCameraRateHz);
    const Eigen::Vector3d cam = balloon + Eigen::Vector3d(-20.0 + 1.4 * i, 0.0, -0.5);
    w.place_camera("uav0_gimbal", cam, look(0.0, 0.0));
    const server::render::CameraFrame f = w.render(0);
    VideoLogFrame frame;
    frame.stamp_us = f.stamp_us;
    frame.image = to_bgr(f);
    // the balloon flown at is the largest (other balloons may show behind it)
    const auto d = detector.detect(frame.image);
    ASSERT_FALSE(d.empty()) << "frame " << i;
    detected.push_back(d[0]);
    const cv::Point2f centre(static_cast<float>(d[0].centre_px.x),
                             static_cast<float>(d[0].centre_px.y));
    frame.overlays.push_back(
        Overlay::circle(centre, static_cast<float>(d[0].radius_px), {0, 0, 255}, 2.0f));
    char label[32];
    std::snprintf(label, sizeof(label), "%.2f m", d[0].range_m);
    frame.overlays.push_back(
        Overlay::label(centre + cv::Point2f(0.0f, -50.0f), label, {255, 255, 255}));
    frame.text = "frame " + std::to_string(i) + " range " + label;
    ASSERT_TRUE((*writer)->submit(frame)) << "frame " << i;
    written.push_back(frame);
  }
  ASSERT_TRUE((*writer)->close().ok());
  EXPECT_EQ((*writer)->frames_written(), static_cast<uint64_t>(kFrames));

  auto reader = VideoLogReader::open(path);
  ASSERT_TRUE(reader.ok());
  ASSERT_EQ((*reader)->frame_count(), static_cast<size_t>(kFrames));
  for (int i = 0; i < kFrames; ++i) {
    auto r = (*reader)->read(i);
    ASSERT_TRUE(r.ok()) << "frame " << i;
    EXPECT_EQ(r->stamp_us, written[i].stamp_us);
    EXPECT_EQ(r->overlays, written[i].overlays);
    EXPECT_EQ(r->text, written[i].text);
    ASSERT_EQ(r->image.size(), written[i].image.size());
    EXPECT_GE(cv::PSNR(r->image, written[i].image), kMinPsnrDb) << "frame " << i;
    // the balloon survives compression: same place, same range
    const auto d = detector.detect(r->image);
    ASSERT_FALSE(d.empty()) << "frame " << i;
    EXPECT_LT(cv::norm(d[0].centre_px - detected[i].centre_px), kCentreTolShare * d[0].radius_px)
        << "frame " << i;
    const double true_range_m = Eigen::Vector3d(-20.0 + 1.4 * i, 0.0, -0.5).norm();
    EXPECT_LT(std::abs(d[0].range_m - true_range_m) / true_range_m, kMaxRangeError) << i;
  }
  // stamps are the sim times of the frames: the reader seeks by them
  EXPECT_EQ((*reader)->index_at(written[5].stamp_us), 5u);
  std::filesystem::remove(path);
}

}  // namespace
}  // namespace uavsim::vision::rendered
