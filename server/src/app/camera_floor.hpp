// The camera frames of --render-cameras: a frame consumer that asks for the named cameras' frames
// at their rates and throws them away, so the server alone does a mission's rendering without the
// mission (the floor of docs/results/performance.md). Its frames are never dropped, as a lockstep
// client's are not: at --rate 0 the clock waits for the renderer, as it does for the mission.
#pragma once

#include <atomic>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "app/render_cameras_option.hpp"
#include "render/frame_service.hpp"

namespace uavsim::server::app {

class CameraFloor : public render::FrameConsumer {
 public:
  // Throws std::invalid_argument, naming the option, for a camera the service does not have (the
  // message lists those it has), a format the camera does not give, or an fps that is not the
  // camera's own divided by a whole number (the rule of camera_subscribe's fps).
  CameraFloor(const std::vector<render::FrameCamera>& cameras,
              const std::vector<RenderCamera>& wanted);

  void want(int camera, int64_t index, int64_t stamp_us,
            std::vector<render::EncodingKey>* encodings, bool* must_deliver) override;
  void dropped(int, int64_t) override {}  // never: every frame is asked for as must_deliver
  void deliver(const render::ReadyFrame& frame) override;

  // Frames delivered so far, in all. Thread-safe.
  uint64_t frames() const;
  // "N camera frames rendered for --render-cameras (CAM M at F fps FORMAT, ...)". Thread-safe;
  // after FrameService::wait_delivered() it counts every frame of the run.
  std::string summary() const;

 private:
  struct Wanted {
    int camera = -1;  // index into the service's cameras
    std::string name;
    render::EncodingKey key;
    int every = 1;  // one frame in every: the camera's fps / the wanted fps
    double fps_hz = 0.0;
    std::atomic<uint64_t> delivered{0};
  };
  std::vector<std::unique_ptr<Wanted>> wanted_;
  std::vector<Wanted*> by_camera_;  // per service camera: its entry, or null
};

}  // namespace uavsim::server::app
