// uavsim::media: OpenCV's image codecs and video files through libuavsim_media_io.so, loaded on
// first use. The same bytes as OpenCV called directly; a module that cannot be loaded fails each
// call the way OpenCV's own failure looks and says where it looked; and the programs a run starts
// (server, mission programs) do not link the codecs, which is what the module is for.
#include "uavsim/media/media_io.hpp"

#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/videoio.hpp>
#include <random>
#include <sstream>
#include <string>
#include <vector>

namespace uavsim::media {
namespace {

namespace fs = std::filesystem;

// a seeded picture with edges and noise, so that the codecs have something to get wrong
cv::Mat test_picture(int w, int h, int channels) {
  cv::Mat m(h, w, CV_8UC(channels));
  std::mt19937 rng(7);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w * channels; ++x)
      m.ptr<uint8_t>(y)[x] = static_cast<uint8_t>(((x / 9 + y / 7) % 2) * 150 + rng() % 60);
  return m;
}

TEST(MediaIo, EncodesAndDecodesTheSameBytesAsOpenCvCalledDirectly) {
  const cv::Mat bgr = test_picture(64, 48, 3);
  for (const auto& [ext, params] : std::vector<std::pair<std::string, std::vector<int>>>{
           {".jpg", {cv::IMWRITE_JPEG_QUALITY, 85}}, {".jpg", {}}, {".png", {}}}) {
    std::vector<uchar> ours, theirs;
    ASSERT_TRUE(encode_image(ext, bgr, &ours, params)) << ext;
    ASSERT_TRUE(cv::imencode(ext, bgr, theirs, params));
    EXPECT_EQ(ours, theirs) << ext;
    const cv::Mat bytes(1, static_cast<int>(ours.size()), CV_8UC1, ours.data());
    for (int flags : {cv::IMREAD_COLOR, cv::IMREAD_UNCHANGED, cv::IMREAD_GRAYSCALE}) {
      const cv::Mat a = decode_image(bytes, flags), b = cv::imdecode(bytes, flags);
      ASSERT_FALSE(a.empty()) << ext << " flags " << flags;
      ASSERT_EQ(a.type(), b.type());
      ASSERT_EQ(a.size(), b.size());
      EXPECT_EQ(cv::norm(a, b, cv::NORM_INF), 0.0) << ext << " flags " << flags;
    }
  }
  // lossless both ways
  std::vector<uchar> png;
  ASSERT_TRUE(encode_image(".png", bgr, &png));
  const cv::Mat back = decode_image(cv::Mat(1, static_cast<int>(png.size()), CV_8UC1, png.data()),
                                    cv::IMREAD_UNCHANGED);
  EXPECT_EQ(cv::norm(back, bgr, cv::NORM_INF), 0.0);
  // garbage decodes to nothing, as cv::imdecode's
  std::vector<uchar> junk(100, 0x5a);
  EXPECT_TRUE(decode_image(cv::Mat(1, 100, CV_8UC1, junk.data()), cv::IMREAD_COLOR).empty());
  EXPECT_EQ(module_error(), "");
}

TEST(MediaIo, WritesImagesAndVideosOpenCvReadsBack) {
  const fs::path dir = fs::path(::testing::TempDir()) / "media_io_test";
  fs::create_directories(dir);
  const cv::Mat bgr = test_picture(64, 48, 3);
  ASSERT_TRUE(write_image((dir / "a.png").string(), bgr));
  EXPECT_EQ(cv::norm(cv::imread((dir / "a.png").string(), cv::IMREAD_UNCHANGED), bgr, cv::NORM_INF),
            0.0);
  EXPECT_FALSE(write_image((dir / "no_such_folder" / "a.png").string(), bgr));

  const std::string video = (dir / "v.mp4").string();
  {
    VideoFileWriter w;
    ASSERT_TRUE(w.open(video, fourcc('m', 'p', '4', 'v'), 10.0, bgr.size()));
    for (int i = 0; i < 10; ++i) w.write(bgr);
  }  // released (finished) by the destructor
  EXPECT_TRUE(ffmpeg_can_open(video));
  cv::VideoCapture cap(video, cv::CAP_FFMPEG);
  EXPECT_EQ(static_cast<int>(cap.get(cv::CAP_PROP_FRAME_COUNT)), 10);
  EXPECT_EQ(fourcc('m', 'p', '4', 'v'), cv::VideoWriter::fourcc('m', 'p', '4', 'v'));
  // a file that is no video
  EXPECT_FALSE(ffmpeg_can_open((dir / "a.png").string() + ".missing"));
  VideoFileWriter nowhere;
  EXPECT_FALSE(nowhere.open((dir / "no_such_folder" / "v.mp4").string(), fourcc('m', 'p', '4', 'v'),
                            10.0, bgr.size()));
  EXPECT_FALSE(nowhere.is_open());
  nowhere.write(bgr);  // a writer that is not open takes frames and does nothing
  fs::remove_all(dir);
}

// In a fresh process (the module is loaded once per process): UAVSIM_MEDIA_IO names the file to
// load. Exits 0 when every call failed as OpenCV's failures look and the error names `path`.
[[noreturn]] void fail_without_module(const std::string& path, const std::string& why) {
  setenv("UAVSIM_MEDIA_IO", path.c_str(), 1);
  const cv::Mat bgr = test_picture(8, 8, 3);
  std::vector<uchar> out;
  bool ok = !encode_image(".jpg", bgr, &out) && out.empty();
  ok = ok && decode_image(cv::Mat(1, 4, CV_8UC1, cv::Scalar(1)), cv::IMREAD_COLOR).empty();
  ok = ok && !write_image(::testing::TempDir() + "/never.png", bgr);
  VideoFileWriter w;
  ok = ok &&
       !w.open(::testing::TempDir() + "/never.mp4", fourcc('m', 'p', '4', 'v'), 10, bgr.size());
  ok = ok && !ffmpeg_can_open("/dev/null");
  const std::string error = module_error();
  ok = ok && error.find(path) != std::string::npos && error.find(why) != std::string::npos &&
       error.find("UAVSIM_MEDIA_IO") != std::string::npos;
  std::fflush(stderr);
  std::_Exit(ok ? 0 : 1);
}

TEST(MediaIoDeathTest, AModuleThatIsNotThereFailsEachCallAndSaysWhereItLooked) {
  GTEST_FLAG_SET(death_test_style, "threadsafe");
  const std::string path = ::testing::TempDir() + "/no_such/libuavsim_media_io.so";
  // said once on stderr, however many calls fail
  EXPECT_EXIT(fail_without_module(path, "not there"), ::testing::ExitedWithCode(0),
              "^uavsim: libuavsim_media_io.so .*cannot be loaded.*\n  "
              ".*no_such/libuavsim_media_io.so: not there\n$");
}

TEST(MediaIoDeathTest, AFileThatIsNotAModuleIsRefusedWithTheLoadersReason) {
  GTEST_FLAG_SET(death_test_style, "threadsafe");
  const std::string path = ::testing::TempDir() + "/not_a_module.so";
  {
    std::FILE* f = std::fopen(path.c_str(), "w");
    ASSERT_NE(f, nullptr);
    std::fputs("this is text, not an ELF shared object\n", f);
    std::fclose(f);
  }
  EXPECT_EXIT(fail_without_module(path, "not_a_module.so: "), ::testing::ExitedWithCode(0),
              "cannot be loaded");
}

// the point of the module: what a run starts loads no codec, no GDAL, no GStreamer, no FFmpeg
TEST(MediaIo, TheProgramsARunStartsDoNotLinkOpenCvsCodecs) {
  std::stringstream programs(UAVSIM_MEDIA_LIGHT_PROGRAMS);
  std::string program;
  int checked = 0;
  while (std::getline(programs, program, '|')) {
    if (program.empty()) continue;
    std::FILE* p = popen(("ldd '" + program + "' 2>&1").c_str(), "r");
    ASSERT_NE(p, nullptr);
    std::string libs;
    char buf[512];
    while (std::fgets(buf, sizeof(buf), p) != nullptr) libs += buf;
    ASSERT_EQ(pclose(p), 0) << program << ": " << libs;
    ASSERT_NE(libs.find("libc.so"), std::string::npos) << program << ": " << libs;
    for (const char* heavy :
         {"libopencv_imgcodecs", "libopencv_videoio", "libgdal", "libgstreamer", "libavcodec"}) {
      EXPECT_EQ(libs.find(heavy), std::string::npos) << program << " links " << heavy;
    }
    ++checked;
  }
  EXPECT_GE(checked, 1);
}

}  // namespace
}  // namespace uavsim::media
