// uavsim-server --record: a short run as fast as possible writes a readable MP4 of the overview camera
// with one frame per 1/15 s of sim time.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iterator>
#include <opencv2/videoio.hpp>
#include <string>

namespace {

#ifdef UAVSIM_SERVER_BIN
TEST(Record, ThreeSecondsMakeAReadableMp4OfAbout45Frames) {
  const std::string out = ::testing::TempDir() + "uavsim_record_test.mp4";
  std::remove(out.c_str());
  const std::string cmd = std::string(UAVSIM_SERVER_BIN) + " " + UAVSIM_MODELS_DIR +
                          "/worlds/mbzirc2020.xml --duration 3 --rate 0 --record " + out +
                          " --api-port -1 --mavlink-port -1 --quiet";
  ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd;
  cv::VideoCapture video(out);
  ASSERT_TRUE(video.isOpened()) << out;
  int frames = 0;
  cv::Mat img;
  while (video.read(img)) {
    EXPECT_EQ(img.cols, 640);
    EXPECT_EQ(img.rows, 480);
    ++frames;
  }
  EXPECT_GE(frames, 44);
  EXPECT_LE(frames, 46);
}

// --record-camera follow with the demo flight: a readable video of the same length, frames not the
// overview's (the camera moves with the vehicles)
TEST(Record, FollowCameraRecordsTheDemoFlight) {
  const std::string out = ::testing::TempDir() + "uavsim_record_follow_test.mp4";
  std::remove(out.c_str());
  const std::string cmd = std::string(UAVSIM_SERVER_BIN) + " " + UAVSIM_MODELS_DIR +
                          "/worlds/mbzirc2020.xml --duration 3 --rate 0 --demo --record " + out +
                          " --record-camera follow --api-port -1 --mavlink-port -1 --quiet >/dev/null";
  (void)std::system(cmd.c_str());  // the demo has not finished after 3 s: its exit status says so
  cv::VideoCapture video(out);
  ASSERT_TRUE(video.isOpened()) << out;
  int frames = 0;
  cv::Mat img;
  while (video.read(img)) ++frames;
  EXPECT_GE(frames, 44);
  EXPECT_LE(frames, 46);
}

// A disk that fills under the recording (the server's file size limit, which ffmpeg inherits, with
// SIGXFSZ ignored so a write past it fails with EFBIG as on a full disk): the server says once that
// the video stops there, naming the file, and the run goes on to its end. (ffmpeg's MP4 muxer
// buffers 32 KiB and, at 8 KiB, fails only on the file's tail, then exits 0: the server finds the
// video unreadable.)
TEST(Record, ADiskFullUnderTheVideoIsSaidOnceAndTheRunGoesOn) {
  const std::string dir = ::testing::TempDir();
  const std::string out = dir + "uavsim_record_full.mp4", err = dir + "uavsim_record_full.err",
                    log = dir + "uavsim_record_full.out";
  std::remove(out.c_str());
  const std::string cmd = "trap '' XFSZ; prlimit --fsize=8192 " + std::string(UAVSIM_SERVER_BIN) +
                          " " + UAVSIM_MODELS_DIR +
                          "/worlds/mbzirc2020.xml --duration 5 --rate 0 --record " + out +
                          " --api-port -1 --mavlink-port -1 > " + log + " 2> " + err;
  const int status = std::system(cmd.c_str());
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << status << ": " << cmd;
  std::ifstream in(err);
  int said = 0;
  std::string text;
  for (std::string line; std::getline(in, line);) {
    text += line + "\n";
    if (line.rfind("uavsim-server: the video stops here: " + out + ": ", 0) == 0) ++said;
  }
  EXPECT_EQ(said, 1) << text;
  std::ifstream out_log(log);
  const std::string summary((std::istreambuf_iterator<char>(out_log)),
                            std::istreambuf_iterator<char>());
  EXPECT_NE(summary.find("ran 5.000 s of sim time"), std::string::npos) << summary;
}

TEST(Record, UnknownVehicleToFollowIsAUsageError) {
  const std::string cmd = std::string(UAVSIM_SERVER_BIN) + " " + UAVSIM_MODELS_DIR +
                          "/worlds/mbzirc2020.xml --duration 1 --rate 0 --record " + ::testing::TempDir() +
                          "x.mp4 --record-camera follow:nobody --api-port -1 --mavlink-port -1 --quiet 2>/dev/null";
  const int status = std::system(cmd.c_str());
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 2) << status;
}
#endif

}  // namespace
