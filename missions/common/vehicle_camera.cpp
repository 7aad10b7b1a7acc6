#include "uavsim/mission/vehicle_camera.hpp"

#include <utility>

namespace uavsim::mission {

bool open_video_log(const ProgramLoop& program, const std::string& path,
                    std::unique_ptr<vision::VideoLogWriter>* out) {
  out->reset();
  if (path.empty()) return true;
  auto opened = vision::VideoLogWriter::open(path, vision::write_error_said_by(program.name()));
  if (!opened) {
    program.log("--video-log " + path + ": " + vision::to_string(opened.error()));
    return false;
  }
  *out = std::move(*opened);
  return true;
}

std::unique_ptr<client::CameraSubscriber> subscribe_camera(
    ProgramLoop& program, const std::string& camera, client::CameraFormat format,
    std::function<void(const client::CameraFrame&)> on_frame) {
  client::CameraConfig cc;
  cc.camera = camera;
  cc.format = format;
  auto sub = client::CameraSubscriber::subscribe(program.loop(), cc, std::move(on_frame));
  if (!sub) {
    program.log("camera " + camera + ": " + sub.message());
    return nullptr;
  }
  return std::move(*sub);
}

}  // namespace uavsim::mission
