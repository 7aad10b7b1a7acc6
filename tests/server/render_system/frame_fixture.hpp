// A running server with cameras, for the frame-service system tests: a world with its objects, the
// frame service, the sim API and (optionally) the MAVLink endpoint with the gimbal bridge and the
// endpoint hooks, wired as server_app.cpp wires them; a Runner on its own thread. FrameClient is
// the client library's SimConnection, which reads frames (a header line, then exactly "bytes" raw
// bytes) with the other messages.
#pragma once

#include <gtest/gtest.h>

#include <limits>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <thread>

#include "api/api_server.hpp"
#include "app/camera_owners.hpp"
#include "app/endpoint_hooks.hpp"
#include "app/gimbal_bridge.hpp"
#include "mavlink/endpoint.hpp"
#include "objects/world_objects.hpp"
#include "physics/world.hpp"
#include "render/camera_setup.hpp"
#include "render/frame_service.hpp"
#include "sim/runner.hpp"
#include "sim_api_client.hpp"

namespace uavsim::server::render::testing {

using Json = nlohmann::json;

struct ServerOptions {
  std::string world = "mbzirc2020.xml";  // in models/worlds, or an absolute path
  std::vector<std::string> camera_overrides;
  double rate = 0.0;
  bool mavlink = false;
  bool start_paused = false;
};

using Hooks = app::EndpointHooks;

class FrameServer {
 public:
  explicit FrameServer(const ServerOptions& o = {}) {
    physics::ComposeOptions co;
    co.models_dir = UAVSIM_MODELS_DIR;
    sim_ = std::make_unique<sim::Simulation>(
        physics::World::load(o.world.front() == '/'
                                 ? o.world
                                 : std::string(UAVSIM_MODELS_DIR) + "/worlds/" + o.world,
                             co),
        sim::SimConfig{});
    objects_ = objects::add_world_objects(*sim_);
    if (o.mavlink) {
      mavlink::EndpointConfig ec;
      ec.base_port = 0;
      mavlink_ = std::make_unique<mavlink::MavlinkServer>(*sim_, ec);
      mavlink_->schedule(sim_->schedule());
      hooks_ = std::make_unique<Hooks>(*mavlink_);
      if (objects_.gimbals) {
        mavlink::MavlinkServer* ms = mavlink_.get();
        bridge_ = std::make_unique<app::MavlinkGimbalBridge>(
            *objects_.gimbals,
            [ms](size_t v) -> const mavlink::GimbalState& { return ms->gimbal(v); });
        sim_->schedule().add(sim::Phase::kPostControl, "gimbal_bridge",
                             [this] { bridge_->update(*sim_); });
      }
    }
    const CameraOwners owners = app::camera_owners(sim_->world(), objects_);
    cameras_ = discover_cameras(sim_->world().model(), owners, o.camera_overrides,
                                1.0 / sim_->control_dt_s());
    FrameServiceOptions fo;
    fo.owners = owners;
    frames_ = std::make_unique<FrameService>(sim_->world().model(), cameras_, fo);
    runner_ = std::make_unique<sim::Runner>(*sim_, o.rate);
    api::ApiConfig config;
    config.port = 0;
    config.start_paused = o.start_paused;
    api_ = std::make_unique<api::ApiServer>(*sim_, runner_.get(), objects_, config);
    if (hooks_) {
      api_->set_link_control(hooks_.get());
      api_->set_seq_waiter(hooks_.get());
    }
    api_->set_frame_service(frames_.get());
    FrameService* fs = frames_.get();
    runner_->add_gate(sim::Phase::kCapture, "frames",
                      [fs, this](double) { fs->capture(sim_->world().data()); });
    runner_->add_gate(sim::Phase::kQueuedTasks, "api", api_->gate());
    api_->start();
    loop_ = std::thread([this] { runner_->run_until(std::numeric_limits<double>::infinity()); });
  }
  ~FrameServer() {
    runner_->stop();
    api_->shutdown();
    loop_.join();
    frames_.reset();
    api_.reset();
    mavlink_.reset();
  }
  uint16_t port() const { return api_->port(); }
  uint16_t mavlink_port(size_t v) const { return mavlink_->port(v); }
  mavlink::MavlinkServer& mavlink() { return *mavlink_; }
  sim::Simulation& sim() {
    return *sim_;
  }  // only while the loop is held (paused, or a lockstep tick)
  FrameService& frames() { return *frames_; }

 private:
  std::unique_ptr<sim::Simulation> sim_;
  objects::ObjectSet objects_;
  std::unique_ptr<mavlink::MavlinkServer> mavlink_;
  std::unique_ptr<Hooks> hooks_;
  std::unique_ptr<app::MavlinkGimbalBridge> bridge_;
  std::vector<CameraSetup> cameras_;
  std::unique_ptr<FrameService> frames_;
  std::unique_ptr<sim::Runner> runner_;
  std::unique_ptr<api::ApiServer> api_;
  std::thread loop_;
};

using api::testing::Message;  // a streamed message: the JSON, and for a frame its image bytes

// The sim API on the client library's SimConnection (frames with their image bytes); waits end
// after 20 s. rcvbuf > 0 sets the socket's receive buffer (a client that reads slowly fills it
// sooner).
class FrameClient : public api::testing::SimApiClient {
 public:
  explicit FrameClient(uint16_t port, int rcvbuf = 0) : SimApiClient(port, rcvbuf, 20.0) {}
};

}  // namespace uavsim::server::render::testing
