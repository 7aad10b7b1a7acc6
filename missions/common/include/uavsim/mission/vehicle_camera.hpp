// A vehicle program's camera and the video log of what its vision saw, opened the same way by each
// mission's UAV program: on failure the reason goes to the program's log and the program gives up.
#pragma once

#include <functional>
#include <memory>
#include <string>

#include "uavsim/client/camera.hpp"
#include "uavsim/mission/program.hpp"
#include "uavsim/vision/video_log.hpp"

namespace uavsim::mission {

// The video log at `path`, its write errors said by the program's name; nullptr in *out when path
// is empty (no log asked for). False after "--video-log PATH: why" in the log. Loop thread only.
bool open_video_log(const ProgramLoop& program, const std::string& path,
                    std::unique_ptr<vision::VideoLogWriter>* out);

// The subscription to `camera`'s frames in `format`, each handed to on_frame on the program's
// loop; nullptr after "camera NAME: why" in the log. Loop thread only.
std::unique_ptr<client::CameraSubscriber> subscribe_camera(
    ProgramLoop& program, const std::string& camera, client::CameraFormat format,
    std::function<void(const client::CameraFrame&)> on_frame);

}  // namespace uavsim::mission
