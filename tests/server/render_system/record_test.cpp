// uavsim-server --record: a short run as fast as possible writes a readable MP4 of the overview camera
// with one frame per 1/15 s of sim time.
#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
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
#endif

}  // namespace
