// uavsim-videolog-export: replays a VLOG file (seed 6.4) into PNG frames and/or an MP4, with the
// overlay drawings and per-frame text painted on (or not).
//
//   uavsim-videolog-export LOG.vlog [--png DIR] [--mp4 FILE] [--no-overlays] [--no-text] [--fps N]
//   uavsim-videolog-export LOG.vlog --info      frame count, time span, and each frame's text
#include <cstdio>
#include <cstdlib>
#include <string>

#include "uavsim/vision/video_log.hpp"

namespace {

int usage() {
  std::fprintf(stderr,
               "usage: uavsim-videolog-export LOG.vlog [--png DIR] [--mp4 FILE] [--no-overlays]\n"
               "                              [--no-text] [--fps N] | --info\n");
  return 2;
}

}  // namespace

int main(int argc, char** argv) {
  using uavsim::vision::VideoLogExportOptions;
  if (argc < 2) return usage();
  const std::string input = argv[1];
  VideoLogExportOptions options;
  bool info = false;
  for (int i = 2; i < argc; ++i) {
    const std::string arg = argv[i];
    auto next = [&]() -> const char* { return i + 1 < argc ? argv[++i] : nullptr; };
    if (arg == "--png") {
      const char* v = next();
      if (!v) return usage();
      options.png_dir = v;
    } else if (arg == "--mp4") {
      const char* v = next();
      if (!v) return usage();
      options.mp4_path = v;
    } else if (arg == "--fps") {
      const char* v = next();
      if (!v) return usage();
      options.fps = std::atof(v);
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
      std::printf("%6zu  t=%.6f s  %dx%d  %zu overlays  %s\n", i, 1e-6 * rec->stamp_us,
                  rec->image.cols, rec->image.rows, rec->overlays.size(), rec->text.c_str());
    }
    return 0;
  }
  if (options.png_dir.empty() && options.mp4_path.empty()) return usage();
  auto result = uavsim::vision::export_video_log(input, options);
  if (!result) {
    std::fprintf(stderr, "%s: %s\n", input.c_str(), uavsim::vision::to_string(result.error()));
    return 1;
  }
  std::printf("exported %zu frames\n", result.value());
  return 0;
}
