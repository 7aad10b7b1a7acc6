#include "uavsim/vision/video_log.hpp"

#include <gtest/gtest.h>
#include <signal.h>
#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <mutex>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <random>
#include <vector>

#include "uavsim/vision/synthetic_scene.hpp"

namespace uavsim::vision {
namespace {

constexpr double kMinPsnrDb = 30.0;  // JPEG at quality 90 on smooth synthetic frames

namespace fs = std::filesystem;

// a fresh directory per test, removed afterwards
class VideoLogTest : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = fs::temp_directory_path() /
           (std::string("uavsim_vlog_") + info->name() + "_" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  fs::path dir_;
};

cv::Mat frame_image(int i) {
  const auto k = PinholeIntrinsics::from_fovy(320, 240, 1.0);
  cv::Mat image = synthetic::sky_sand_background(k, 60 + 4 * i, 100 + i);
  synthetic::render_sphere(k, {0.2 * (i - 5), 0.0, 6.0}, 0.6, {40, 170, 50}, {0, -1, 0}, &image);
  return image;
}

std::vector<Overlay> frame_overlays(int i) {
  return {Overlay::circle({100.5f + i, 80.25f}, 12.5f, {0, 255, 0}, 2.0f),
          Overlay::line({0, 0}, {319, 239}, {255, 0, 0}),
          Overlay::rectangle({10, 20, 30.5f, 40}, {0, 0, 255}, 3.0f),
          Overlay::label({5, 230}, "balloon #" + std::to_string(i), {255, 255, 255}, 0.4f)};
}

TEST_F(VideoLogTest, RoundTripKeepsFramesStampsOverlaysAndText) {
  constexpr int kFrames = 12;
  {
    auto writer = VideoLogWriter::open(dir_ / "a.vlog", {90, 64, nullptr});
    ASSERT_TRUE(writer.ok());
    for (int i = 0; i < kFrames; ++i) {
      VideoLogFrame f{1'000'000 + 142'857LL * i, frame_image(i), frame_overlays(i),
                      "range=" + std::to_string(10 - i) + " m\nstate=APPROACH"};
      ASSERT_TRUE((*writer)->submit(f));
    }
    ASSERT_TRUE((*writer)->close().ok());
    EXPECT_EQ((*writer)->frames_written(), static_cast<uint64_t>(kFrames));
    EXPECT_EQ((*writer)->frames_dropped(), 0u);
  }
  auto reader = VideoLogReader::open(dir_ / "a.vlog");
  ASSERT_TRUE(reader.ok());
  VideoLogReader& log = *reader.value();
  ASSERT_EQ(log.frame_count(), static_cast<size_t>(kFrames));
  // seek backwards first: random access works by index
  for (int i = kFrames - 1; i >= 0; --i) {
    auto rec = log.read(i);
    ASSERT_TRUE(rec.ok()) << to_string(rec.error());
    EXPECT_EQ(rec->stamp_us, 1'000'000 + 142'857LL * i);
    EXPECT_TRUE(rec->keyframe);
    EXPECT_EQ(rec->overlays, frame_overlays(i));
    EXPECT_EQ(rec->text, "range=" + std::to_string(10 - i) + " m\nstate=APPROACH");
    EXPECT_GT(cv::PSNR(rec->image, frame_image(i)), kMinPsnrDb);
  }
  EXPECT_EQ(log.index_at(1'000'000 + 142'857LL * 5 + 1), 5u);
  EXPECT_FALSE(log.read(kFrames).ok());
  EXPECT_EQ(log.read(kFrames).error(), VideoLogError::kOutOfRange);
}

TEST_F(VideoLogTest, FullQueueDropsAndCountsInsteadOfBlocking) {
  auto writer = VideoLogWriter::open(dir_ / "b.vlog", {95, 2, nullptr});
  ASSERT_TRUE(writer.ok());
  // 1280x960 noise is slow to encode: submitting 100 back to back must overflow a 2-frame queue
  cv::Mat big(960, 1280, CV_8UC3);
  cv::randu(big, 0, 255);
  int accepted = 0;
  for (int i = 0; i < 100; ++i) accepted += (*writer)->submit({i * 1000LL, big, {}, ""});
  ASSERT_TRUE((*writer)->close().ok());
  EXPECT_GT((*writer)->frames_dropped(), 0u);
  EXPECT_EQ((*writer)->frames_written() + (*writer)->frames_dropped(), 100u);
  EXPECT_EQ((*writer)->frames_written(), static_cast<uint64_t>(accepted));
  auto reader = VideoLogReader::open(dir_ / "b.vlog");
  ASSERT_TRUE(reader.ok());
  EXPECT_EQ((*reader)->frame_count(), static_cast<size_t>(accepted));
  // submit after close is a drop, not a crash
  EXPECT_FALSE((*writer)->submit({0, big, {}, ""}));
}

TEST_F(VideoLogTest, TruncatedLogReadsUpToLastWholeFrame) {
  {
    auto writer = VideoLogWriter::open(dir_ / "c.vlog");
    ASSERT_TRUE(writer.ok());
    for (int i = 0; i < 5; ++i) (*writer)->submit({i * 100'000LL, frame_image(i), {}, "x"});
    ASSERT_TRUE((*writer)->close().ok());
  }
  // a crash mid-write: cut the last record in half
  const auto size = fs::file_size(dir_ / "c.vlog");
  ASSERT_EQ((*VideoLogReader::open(dir_ / "c.vlog"))->frame_count(), 5u);
  fs::resize_file(dir_ / "c.vlog", size - 500);  // a JPEG record is several kB
  auto reader = VideoLogReader::open(dir_ / "c.vlog");
  ASSERT_TRUE(reader.ok());
  EXPECT_EQ((*reader)->frame_count(), 4u);
  EXPECT_TRUE((*reader)->read(3).ok());
}

// Byte offsets where the VLOG's records end, following the size prefixes from the 16-byte header
// (little-endian u32 per record); the last is where the chain stops.
std::vector<uint64_t> record_ends(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  std::vector<uint64_t> ends;
  uint64_t pos = 16;
  while (pos + 4 <= bytes.size()) {
    uint32_t n = 0;
    for (int i = 0; i < 4; ++i)
      n |= static_cast<uint32_t>(static_cast<uint8_t>(bytes[pos + i])) << (8 * i);
    if (pos + 4 + n > bytes.size()) break;
    pos += 4 + n;
    ends.push_back(pos);
  }
  return ends;
}

// A disk that fills mid-log (this process's file size limit, RLIMIT_FSIZE, with SIGXFSZ ignored so
// a write past it fails with EFBIG as one on a full disk fails with ENOSPC): the log ends on its
// last whole frame, the failure is said once naming the file, later frames are dropped and close()
// says the log is incomplete.
TEST_F(VideoLogTest, ADiskFullMidLogEndsOnAWholeFrameAndIsSaidOnce) {
  constexpr rlim_t kLimitBytes = 48 * 1024;  // a few 320x240 JPEG frames
  constexpr int kFrames = 20;
  const fs::path path = dir_ / "full.vlog";
  std::vector<std::string> said;
  std::mutex said_mutex;
  VideoLogWriterOptions options;
  options.queue_capacity = kFrames;  // no drop for a full queue: every drop is the disk's
  options.on_write_error = [&](const std::string& why) {
    std::lock_guard lock(said_mutex);
    said.push_back(why);
  };
  rlimit old{};
  ASSERT_EQ(getrlimit(RLIMIT_FSIZE, &old), 0);
  const rlimit limited{std::min(kLimitBytes, old.rlim_cur), old.rlim_max};
  const auto old_handler = signal(SIGXFSZ, SIG_IGN);
  ASSERT_EQ(setrlimit(RLIMIT_FSIZE, &limited), 0);
  auto writer = VideoLogWriter::open(path, options);
  bool closed_ok = true;
  if (writer.ok()) {
    for (int i = 0; i < kFrames; ++i) (*writer)->submit({i * 100'000LL, frame_image(i), {}, "x"});
    closed_ok = (*writer)->close().ok();
  }
  ASSERT_EQ(setrlimit(RLIMIT_FSIZE, &old), 0);  // before any assertion can return early
  signal(SIGXFSZ, old_handler);
  ASSERT_TRUE(writer.ok());
  EXPECT_FALSE(closed_ok);
  ASSERT_EQ(said.size(), 1u);
  EXPECT_EQ(said[0], path.string() + ": File too large");
  EXPECT_EQ((*writer)->write_error(), said[0]);
  const uint64_t written = (*writer)->frames_written();
  EXPECT_GE(written, 1u);
  EXPECT_LT(written, static_cast<uint64_t>(kFrames));
  EXPECT_EQ(written + (*writer)->frames_dropped(), static_cast<uint64_t>(kFrames));
  // no torn frame: the records chain to the file's last byte, and each one reads back
  const std::vector<uint64_t> ends = record_ends(path);
  ASSERT_EQ(ends.size(), written);
  EXPECT_EQ(ends.back(), fs::file_size(path));
  auto reader = VideoLogReader::open(path);
  ASSERT_TRUE(reader.ok());
  ASSERT_EQ((*reader)->frame_count(), written);
  for (size_t i = 0; i < written; ++i) EXPECT_TRUE((*reader)->read(i).ok()) << i;
}

// a camera's depth and segmentation beside the image come back bit for bit (NaN included)
TEST_F(VideoLogTest, DepthAndSegmentationPlanesRoundTripExactly) {
  const cv::Mat image = frame_image(3);
  cv::Mat depth(image.size(), CV_32FC1), objects(image.size(), CV_16UC1), classes(image.size(), CV_16UC1);
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> metres(0.1f, 500.0f);
  for (int v = 0; v < image.rows; ++v) {
    for (int u = 0; u < image.cols; ++u) {
      depth.at<float>(v, u) = (u + v) % 17 == 0 ? std::numeric_limits<float>::quiet_NaN() : metres(rng);
      objects.at<uint16_t>(v, u) = static_cast<uint16_t>((u * 7 + v) % 65536);
      classes.at<uint16_t>(v, u) = static_cast<uint16_t>(v % 8);
    }
  }
  {
    auto writer = VideoLogWriter::open(dir_ / "p.vlog");
    ASSERT_TRUE(writer.ok());
    VideoLogFrame with{42, image, {}, "rgbd"};
    with.depth_m = depth;
    with.object_ids = objects;
    with.class_ids = classes;
    ASSERT_TRUE((*writer)->submit(with));
    ASSERT_TRUE((*writer)->submit(VideoLogFrame{43, image, {}, "colour only"}));
    // planes of another size or type are refused
    VideoLogFrame wrong{44, image, {}, ""};
    wrong.depth_m = cv::Mat(10, 10, CV_32FC1, cv::Scalar(1.0f));
    EXPECT_FALSE((*writer)->submit(wrong));
    wrong.depth_m = cv::Mat(image.size(), CV_64FC1, cv::Scalar(1.0));
    EXPECT_FALSE((*writer)->submit(wrong));
    ASSERT_TRUE((*writer)->close().ok());
  }
  auto reader = VideoLogReader::open(dir_ / "p.vlog");
  ASSERT_TRUE(reader.ok());
  ASSERT_EQ((*reader)->frame_count(), 2u);
  auto rec = (*reader)->read(0);
  ASSERT_TRUE(rec.ok()) << to_string(rec.error());
  ASSERT_EQ(rec->depth_m.type(), CV_32FC1);
  ASSERT_EQ(rec->depth_m.size(), image.size());
  EXPECT_EQ(std::memcmp(rec->depth_m.data, depth.data, depth.total() * 4), 0) << "depth not bit-exact";
  EXPECT_EQ(cv::norm(rec->object_ids, objects, cv::NORM_INF), 0.0);
  EXPECT_EQ(cv::norm(rec->class_ids, classes, cv::NORM_INF), 0.0);
  auto plain = (*reader)->read(1);
  ASSERT_TRUE(plain.ok());
  EXPECT_TRUE(plain->depth_m.empty());
  EXPECT_TRUE(plain->object_ids.empty());
  EXPECT_EQ(plain->text, "colour only");
}

// logs written before the planes (version 1) still read
TEST_F(VideoLogTest, VersionOneLogsStillRead) {
  std::vector<uchar> jpeg;
  ASSERT_TRUE(cv::imencode(".jpg", frame_image(0), jpeg));
  std::string b("UAVVLOG\0", 8);
  auto u32 = [&b](uint32_t v) {
    for (int i = 0; i < 4; ++i) b.push_back(static_cast<char>((v >> (8 * i)) & 0xff));
  };
  u32(1);
  u32('M' | ('J' << 8) | ('P' << 16) | ('G' << 24));
  const uint32_t record = 8 + 1 + 4 + static_cast<uint32_t>(jpeg.size()) + 4 + 4 + 2;
  u32(record);
  for (int i = 0; i < 8; ++i) b.push_back(static_cast<char>(i == 0 ? 77 : 0));  // stamp 77 us
  b.push_back(1);
  u32(static_cast<uint32_t>(jpeg.size()));
  b.append(reinterpret_cast<const char*>(jpeg.data()), jpeg.size());
  u32(0);  // overlays
  u32(2);
  b += "v1";
  std::ofstream(dir_ / "v1.vlog", std::ios::binary) << b;
  auto reader = VideoLogReader::open(dir_ / "v1.vlog");
  ASSERT_TRUE(reader.ok());
  ASSERT_EQ((*reader)->frame_count(), 1u);
  auto rec = (*reader)->read(0);
  ASSERT_TRUE(rec.ok()) << to_string(rec.error());
  EXPECT_EQ(rec->stamp_us, 77);
  EXPECT_EQ(rec->text, "v1");
  EXPECT_TRUE(rec->depth_m.empty());
}

TEST_F(VideoLogTest, RejectsForeignFiles) {
  std::ofstream(dir_ / "junk.vlog") << "this is not a video log at all";
  auto reader = VideoLogReader::open(dir_ / "junk.vlog");
  ASSERT_FALSE(reader.ok());
  EXPECT_EQ(reader.error(), VideoLogError::kBadFormat);
  EXPECT_EQ(VideoLogReader::open(dir_ / "missing.vlog").error(), VideoLogError::kOpenFailed);
}

TEST_F(VideoLogTest, ExportPaintsOverlaysIntoPngsAndMp4) {
  {
    auto writer = VideoLogWriter::open(dir_ / "d.vlog");
    ASSERT_TRUE(writer.ok());
    for (int i = 0; i < 6; ++i) {
      (*writer)->submit(
          {i * 100'000LL, frame_image(i), frame_overlays(i), "frame " + std::to_string(i)});
    }
    ASSERT_TRUE((*writer)->close().ok());
  }
  VideoLogExportOptions options;
  options.png_dir = dir_ / "png";
  options.mp4_path = dir_ / "d.mp4";
  auto exported = export_video_log(dir_ / "d.vlog", options);
  ASSERT_TRUE(exported.ok()) << to_string(exported.error());
  EXPECT_EQ(exported.value(), 6u);
  EXPECT_TRUE(fs::exists(dir_ / "png" / "frame_000005.png"));
  EXPECT_GT(fs::file_size(dir_ / "d.mp4"), 1000u);
  // the red rectangle (BGR 0,0,255) of frame 0 is painted: its left edge at x = 10, y = 20..60
  const cv::Mat png = cv::imread((dir_ / "png" / "frame_000000.png").string());
  const cv::Vec3b px = png.at<cv::Vec3b>(40, 10);
  EXPECT_GT(px[2], 200);
  EXPECT_LT(px[1], 60);
  // without overlays the same pixel is the sky again
  options.draw_overlays = false;
  options.draw_text = false;
  options.mp4_path.clear();
  options.png_dir = dir_ / "raw";
  ASSERT_TRUE(export_video_log(dir_ / "d.vlog", options).ok());
  const cv::Mat raw = cv::imread((dir_ / "raw" / "frame_000000.png").string());
  EXPECT_GT(raw.at<cv::Vec3b>(40, 10)[0], 200);  // sky: blue channel high
}

}  // namespace
}  // namespace uavsim::vision
