#include "app/camera_floor.hpp"

#include <cmath>
#include <sstream>
#include <stdexcept>

#include "api/frame_stream.hpp"

namespace uavsim::server::app {

CameraFloor::CameraFloor(const std::vector<render::FrameCamera>& cameras,
                         const std::vector<RenderCamera>& wanted)
    : by_camera_(cameras.size(), nullptr) {
  for (const RenderCamera& w : wanted) {
    const std::string entry = "--render-cameras " + w.camera;
    std::size_t c = 0;
    while (c < cameras.size() && cameras[c].name != w.camera) ++c;
    if (c == cameras.size()) {
      std::string names;
      for (const render::FrameCamera& k : cameras) names += (names.empty() ? "" : ", ") + k.name;
      throw std::invalid_argument(
          entry + ": no such camera (cameras: " + (names.empty() ? "none" : names) + ")");
    }
    const render::FrameCamera& info = cameras[c];
    auto e = std::make_unique<Wanted>();
    e->camera = static_cast<int>(c);
    e->name = w.camera;
    e->key.encoding = render::encoding_from_name(w.format).value();  // checked by the options
    if (!render::gives(info.modalities, e->key.encoding)) {
      throw std::invalid_argument(entry + ": the camera gives no " + w.format + " images");
    }
    e->fps_hz = w.fps_hz.value_or(info.fps_hz);
    const std::optional<int> every = api::frame_divisor(info.fps_hz, e->fps_hz);
    if (!every) {
      std::ostringstream m;
      m << entry << "@" << e->fps_hz << ": the fps must be the camera's (" << info.fps_hz
        << ") divided by a whole number up to " << api::kMaxFrameDivisor;
      throw std::invalid_argument(m.str());
    }
    e->every = *every;
    e->fps_hz = info.fps_hz / *every;
    by_camera_[c] = e.get();
    wanted_.push_back(std::move(e));
  }
}

void CameraFloor::want(int camera, int64_t index, int64_t,
                       std::vector<render::EncodingKey>* encodings, bool* must_deliver) {
  const Wanted* w = by_camera_[static_cast<std::size_t>(camera)];
  if (w == nullptr || index % w->every != 0) return;
  encodings->push_back(w->key);
  *must_deliver = true;
}

void CameraFloor::deliver(const render::ReadyFrame& frame) {
  if (Wanted* w = by_camera_[static_cast<std::size_t>(frame.camera)]) ++w->delivered;
}

uint64_t CameraFloor::frames() const {
  uint64_t n = 0;
  for (const auto& w : wanted_) n += w->delivered;
  return n;
}

std::string CameraFloor::summary() const {
  std::ostringstream s;
  s << frames() << " camera frames rendered for --render-cameras (";
  for (std::size_t i = 0; i < wanted_.size(); ++i) {
    const Wanted& w = *wanted_[i];
    s << (i ? ", " : "") << w.name << " " << w.delivered << " at " << w.fps_hz << " fps "
      << render::encoding_name(w.key.encoding);
  }
  s << ")";
  return s.str();
}

}  // namespace uavsim::server::app
