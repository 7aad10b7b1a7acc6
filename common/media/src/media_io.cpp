#include "uavsim/media/media_io.hpp"

#include <dlfcn.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <mutex>
#include <system_error>

#include "media_io_table.hpp"
#include "uavsim/common/install_paths.hpp"

namespace uavsim::media {

namespace {

namespace fs = std::filesystem;
using detail::MediaIoTable;

constexpr const char* kModuleName = "libuavsim_media_io.so";

struct Module {
  const MediaIoTable* table = nullptr;
  std::string error;
};

// the folder of the file that holds this code: the program, or a shared object (the Python module)
// that linked this library in
std::string holder_dir() {
  Dl_info info{};
  if (dladdr(reinterpret_cast<void*>(&holder_dir), &info) == 0 || info.dli_fname == nullptr)
    return {};
  std::error_code ec;
  const fs::path p = fs::canonical(info.dli_fname, ec);
  return ec ? std::string() : p.parent_path().string();
}

std::vector<std::string> candidates() {
  if (const char* env = std::getenv("UAVSIM_MEDIA_IO"); env != nullptr && *env != '\0')
    return {env};
  std::vector<std::string> out;
  // each place once (a program holds this code itself: its folder would come twice)
  auto add = [&out](const fs::path& p) {
    const std::string path = p.lexically_normal().string();
    if (std::find(out.begin(), out.end(), path) == out.end()) out.push_back(path);
  };
  for (const std::string& dir : {holder_dir(), common::executable_dir()}) {
    if (dir.empty()) continue;
    add(fs::path(dir) / ".." / UAVSIM_MEDIA_IO_INSTALL_SUBDIR / kModuleName);
    add(fs::path(dir) / kModuleName);
  }
  add(UAVSIM_MEDIA_IO_BUILT);
  // a program of one's own, linked against an installed client library: the prefix this build was
  // configured with, then the system's two (the .deb installs under /usr whatever the build's prefix)
  for (const char* prefix : {UAVSIM_MEDIA_IO_CONFIGURED_PREFIX, "/usr", "/usr/local"})
    add(fs::path(prefix) / UAVSIM_MEDIA_IO_INSTALL_SUBDIR / kModuleName);
  return out;
}

Module load() {
  Module m;
  std::string tried;
  for (const std::string& path : candidates()) {
    std::error_code ec;
    if (!fs::is_regular_file(path, ec)) {
      tried += "\n  " + path + ": not there";
      continue;
    }
    // never closed: OpenCV's codecs keep global state and threads of their own
    void* handle = dlopen(path.c_str(), RTLD_NOW | RTLD_LOCAL);
    if (handle == nullptr) {
      const char* why = dlerror();
      tried += "\n  " + path + ": " + (why != nullptr ? why : "dlopen failed");
      continue;
    }
    using Entry = const MediaIoTable* (*)();
    auto entry = reinterpret_cast<Entry>(dlsym(handle, "uavsim_media_io_table"));
    const MediaIoTable* table = entry != nullptr ? entry() : nullptr;
    if (table == nullptr || table->abi_version != detail::kMediaIoAbiVersion ||
        table->table_size != sizeof(MediaIoTable)) {
      tried += "\n  " + path + ": from another build of uavsim (its entry points differ)";
      continue;
    }
    m.table = table;
    return m;
  }
  m.error = std::string(kModuleName) +
            " (OpenCV's image codecs and video files) cannot be loaded;" +
            " set UAVSIM_MEDIA_IO to its path. Tried:" + tried;
  return m;
}

const Module& module() {
  static const Module m = load();
  return m;
}

// the module's table, or nullptr after saying once why not
const MediaIoTable* table() {
  const Module& m = module();
  if (m.table == nullptr) {
    static std::once_flag said;
    std::call_once(said, [&] { std::fprintf(stderr, "uavsim: %s\n", m.error.c_str()); });
  }
  return m.table;
}

}  // namespace

bool encode_image(const std::string& ext, const cv::Mat& image, std::vector<uchar>* out,
                  const std::vector<int>& params) {
  const MediaIoTable* t = table();
  return t != nullptr && t->encode(ext, image, out, params);
}

cv::Mat decode_image(const cv::Mat& bytes, int flags) {
  const MediaIoTable* t = table();
  return t != nullptr ? t->decode(bytes, flags) : cv::Mat();
}

bool write_image(const std::string& path, const cv::Mat& image) {
  const MediaIoTable* t = table();
  return t != nullptr && t->write(path, image);
}

bool VideoFileWriter::open(const std::string& path, int fourcc, double fps, cv::Size size,
                           bool is_color) {
  release();
  const MediaIoTable* t = table();
  if (t != nullptr) writer_ = t->video_open(path, fourcc, fps, size, is_color);
  return writer_ != nullptr;
}

void VideoFileWriter::write(const cv::Mat& frame) {
  if (writer_ != nullptr) module().table->video_write(writer_, frame);
}

void VideoFileWriter::release() {
  if (writer_ == nullptr) return;
  module().table->video_close(writer_);
  writer_ = nullptr;
}

bool ffmpeg_can_open(const std::string& path) {
  const MediaIoTable* t = table();
  return t != nullptr && t->ffmpeg_can_open(path);
}

std::string module_error() { return module().error; }

}  // namespace uavsim::media
