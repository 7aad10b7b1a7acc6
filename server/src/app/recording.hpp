// What uavsim-server --record films and writes on it (server_app wires it; bench/record_bench.cpp
// measures it): the camera, the director of a followed view, and the overlay's source. None of it
// exists in a run without --record.
#pragma once

#include <cstddef>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "api/overlay_ops.hpp"
#include "app/run_reporter.hpp"
#include "objects/world_objects.hpp"
#include "render/camera_director.hpp"
#include "render/camera_setup.hpp"
#include "render/frame_service.hpp"
#include "render/overlay.hpp"
#include "sim/simulation.hpp"

namespace uavsim::server::app {

// Which camera --record films for --record-camera `choice`: the named camera, else (overview,
// follow, follow:NAME, top) the world camera "overview", else the first world camera, else the
// first; nullopt for a name no camera has. Thread-safe (pure).
std::optional<size_t> record_camera(const std::vector<render::CameraSetup>& cameras,
                                    const std::string& choice);

// The director of --record-camera follow|follow:NAME|top for the filmed camera `cam` (null for a
// camera posed by the model). Throws std::invalid_argument for a vehicle name the world does not
// have. Loop thread, before the run.
std::shared_ptr<render::CameraDirector> record_director(const std::string& choice,
                                                        const render::FrameCamera& cam,
                                                        const sim::Simulation& s);

// The overlay of each recorded frame, called by the recorder on the loop thread at the frame's
// instant: sim time, the vehicles' names, modes and 10 s trails, the places of pops, landings on
// the target, crashes and kills, the events of the last 4 s (the failsafes reporter saw and the
// launchers' notes among them), the balloon and landing counters and the launchers' counters. s,
// objects' balloons, reporter and notes must outlive the function.
std::function<render::OverlayInfo()> record_overlay_source(sim::Simulation& s,
                                                           const objects::ObjectSet& objects,
                                                           const RunReporter& reporter,
                                                           const api::OverlayOps& notes);

}  // namespace uavsim::server::app
