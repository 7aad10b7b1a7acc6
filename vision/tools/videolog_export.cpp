// uavsim-videolog-export: replays a VLOG file (seed 6.4) into PNG frames and/or an MP4, with the
// overlay drawings and per-frame text painted on (or not); the image, or the camera's depth or
// segmentation planes that a version 2 log holds beside it.
//
//   uavsim-videolog-export LOG.vlog [--png DIR] [--mp4 FILE] [--raw DIR] [--plane P] [--depth-near
//   M]
//                          [--depth-far M] [--no-overlays] [--no-text] [--fps N]
//   uavsim-videolog-export LOG.vlog --info      frame count, time span, each frame's planes and
//   text
//
// Two kinds of output for a plane, because a researcher needs both:
// - pictures (--png, --mp4) to look at: depth in false colour (turbo, log-scaled between
// --depth-near
//   and --depth-far, NaN black: the server's --record-tile depth mapping, so an export looks like
//   the run's video), ids in a fixed colour per id (the same id the same colour in every frame and
//   log), with the vision's overlays on top if wanted (a detector's circles over the ground truth);
// - the plane exactly as logged (--raw), one NumPy .npy per frame (float32 metres with NaN, uint16
//   ids): a 16-bit PNG would quantise depth, clip it at 65 m and merge "nothing measured" with 0,
//   and .npy needs no decoder beyond numpy.load to score a detector or build a training set.
#include <cstdio>
#include <cstdlib>
#include <optional>
#include <string>

#include "uavsim/common/parse_number.hpp"
#include "uavsim/vision/video_log.hpp"

namespace {

using uavsim::vision::VideoLogPlane;

int usage() {
  std::fprintf(
      stderr,
      "usage: uavsim-videolog-export LOG.vlog [--png DIR] [--mp4 FILE] [--raw DIR] [--plane P]\n"
      "                              [--depth-near M] [--depth-far M] [--no-overlays] [--no-text]\n"
      "                              [--fps N] | --info\n"
      "  --plane P        what the PNGs and MP4 show: image (default), depth (false colour),\n"
      "                   objects or classes (segmentation ids, a colour per id)\n"
      "  --depth-near M, --depth-far M\n"
      "                   the depth colours' range in metres (default 1 and 100; 0 < near < far\n"
      "                   <= 1e6): red at near, blue at far, log-scaled; black: nothing measured\n"
      "  --raw DIR        the plane exactly, PLANE_000000.npy per frame (float32 metres, NaN:\n"
      "                   nothing measured; uint16 ids); depth, objects or classes only\n"
      "  --fps N          the MP4's rate, 0 < N <= 1000 (default: from the stamps)\n");
  return 2;
}

std::optional<VideoLogPlane> plane_named(const std::string& name) {
  for (VideoLogPlane p : {VideoLogPlane::kImage, VideoLogPlane::kDepth, VideoLogPlane::kObjectIds,
                          VideoLogPlane::kClassIds}) {
    if (name == uavsim::vision::to_string(p)) return p;
  }
  return std::nullopt;
}

// the planes a record holds, for --info and the "no such plane" message
std::string planes_of(const uavsim::vision::VideoLogRecord& rec) {
  std::string s = "image";
  if (!rec.depth_m.empty()) s += "+depth";
  if (!rec.object_ids.empty()) s += "+objects";
  if (!rec.class_ids.empty()) s += "+classes";
  return s;
}

int bad_option(const std::string& option, const char* value, const char* range) {
  std::fprintf(stderr, "uavsim-videolog-export: %s %s: must be %s\n", option.c_str(),
               value ? value : "(missing)", range);
  return 2;
}

}  // namespace

int main(int argc, char** argv) {
  using uavsim::common::parse_double;
  using uavsim::vision::VideoLogError;
  using uavsim::vision::VideoLogExportOptions;
  if (argc < 2) return usage();
  const std::string input = argv[1];
  VideoLogExportOptions options;
  bool info = false;
  for (int i = 2; i < argc; ++i) {
    const std::string arg = argv[i];
    auto next = [&]() -> const char* { return i + 1 < argc ? argv[++i] : nullptr; };
    if (arg == "--png" || arg == "--mp4" || arg == "--raw") {
      const char* v = next();
      if (!v || !*v) return usage();
      (arg == "--png" ? options.png_dir : arg == "--mp4" ? options.mp4_path : options.raw_dir) = v;
    } else if (arg == "--fps") {
      const char* v = next();
      if (!parse_double(v, 0.0, uavsim::vision::kMaxExportFps, &options.fps) || options.fps <= 0.0)
        return bad_option(arg, v, "a rate in (0, 1000] frames/s");
    } else if (arg == "--depth-near" || arg == "--depth-far") {
      const char* v = next();
      double* out = arg == "--depth-near" ? &options.depth_near_m : &options.depth_far_m;
      if (!parse_double(v, 0.0, uavsim::vision::kMaxExportDepthM, out) || *out <= 0.0)
        return bad_option(arg, v, "metres in (0, 1e6]");
    } else if (arg == "--plane") {
      const char* v = next();
      const auto plane = v ? plane_named(v) : std::nullopt;
      if (!plane) return bad_option(arg, v, "image, depth, objects or classes");
      options.plane = *plane;
    } else if (arg == "--no-overlays") {
      options.draw_overlays = false;
    } else if (arg == "--no-text") {
      options.draw_text = false;
    } else if (arg == "--info") {
      info = true;
    } else {
      return usage();
    }
  }
  if (options.depth_near_m >= options.depth_far_m) {
    std::fprintf(stderr, "uavsim-videolog-export: --depth-near %g must be below --depth-far %g\n",
                 options.depth_near_m, options.depth_far_m);
    return 2;
  }
  if (!options.raw_dir.empty() && options.plane == VideoLogPlane::kImage) {
    std::fprintf(stderr,
                 "uavsim-videolog-export: --raw needs --plane depth, objects or classes (the image "
                 "is JPEG in the log: --png is its lossless picture)\n");
    return 2;
  }

  if (info) {
    auto reader = uavsim::vision::VideoLogReader::open(input);
    if (!reader) {
      std::fprintf(stderr, "%s: %s\n", input.c_str(), uavsim::vision::to_string(reader.error()));
      return 1;
    }
    auto& log = *reader.value();
    std::printf("%zu frames\n", log.frame_count());
    for (size_t i = 0; i < log.frame_count(); ++i) {
      auto rec = log.read(i);
      if (!rec) {
        std::fprintf(stderr, "frame %zu: %s\n", i, uavsim::vision::to_string(rec.error()));
        return 1;
      }
      std::printf("%6zu  t=%.6f s  %dx%d  %s  %zu overlays  %s\n", i, 1e-6 * rec->stamp_us,
                  rec->image.cols, rec->image.rows, planes_of(*rec).c_str(), rec->overlays.size(),
                  rec->text.c_str());
    }
    return 0;
  }
  if (options.png_dir.empty() && options.mp4_path.empty() && options.raw_dir.empty())
    return usage();
  auto result = uavsim::vision::export_video_log(input, options);
  if (!result) {
    std::fprintf(stderr, "%s: %s", input.c_str(), uavsim::vision::to_string(result.error()));
    if (result.error() == VideoLogError::kNoSuchPlane) {
      // name what the log holds (its first frame's planes)
      std::string has = "no readable frame";
      auto reader = uavsim::vision::VideoLogReader::open(input);
      if (reader && reader.value()->frame_count() > 0) {
        auto first = reader.value()->read(0);
        if (first) has = planes_of(*first);
      }
      std::fprintf(stderr, " (%s; the log has %s)", uavsim::vision::to_string(options.plane),
                   has.c_str());
    }
    std::fprintf(stderr, "\n");
    return 1;
  }
  std::printf("exported %zu frames (%s)\n", result.value(),
              uavsim::vision::to_string(options.plane));
  return 0;
}
