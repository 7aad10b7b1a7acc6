// A paused server on the MBZIRC 2020 world (two quads, its objects) with the radio and the GCS-link
// relay served as server_app wires them, on the channel backend asked for: the radio API tests and
// the API chaos tests run against it.
#pragma once

#include <limits>
#include <memory>
#include <string>
#include <thread>

#include "api/radio_ops.hpp"
#include "api_fixture.hpp"
#include "radio/gcs_relay.hpp"
#include "radio/sim_radio.hpp"

namespace uavsim::server::api::testing {

class RadioServer {
 public:
  // allow_remote_gcs: gcs_link_open may aim at any host (false: only at the client's own address, as
  // uavsim-server without --allow-remote-gcs)
  explicit RadioServer(radio::Backend backend = radio::Backend::kSimple, bool allow_remote_gcs = true) {
    physics::ComposeOptions o;
    o.models_dir = UAVSIM_MODELS_DIR;
    sim_ = std::make_unique<sim::Simulation>(
        physics::World::load(std::string(UAVSIM_MODELS_DIR) + "/worlds/mbzirc2020.xml", o),
        sim::SimConfig{});
    objects_ = objects::add_world_objects(*sim_);
    radio::BackendOptions b;
    b.backend = backend;
    radio::SimRadio& radio = radio::SimRadio::attach(*sim_, radio::RadioConfig{}, b);
    radio::GcsRelaySet& relays = radio::GcsRelaySet::attach(*sim_, "127.0.0.1");
    // the policy asks the API server (made below, before any request) for a connection's address
    GcsTargetPolicy targets{allow_remote_gcs, [this](uint64_t conn) { return api_->peer_address(conn); }};
    ops_ = std::make_unique<RadioOps>(*sim_, radio, &relays, std::move(targets));
    runner_ = std::make_unique<sim::Runner>(*sim_, 0.0);
    ApiConfig config;
    config.port = 0;
    config.start_paused = true;
    api_ = std::make_unique<ApiServer>(*sim_, runner_.get(), objects_, config);
    api_->add_group(ops_.get());
    runner_->add_gate(sim::Phase::kQueuedTasks, "api", api_->gate());
    api_->start();
    loop_ = std::thread([this] { runner_->run_until(std::numeric_limits<double>::infinity()); });
  }
  ~RadioServer() {
    runner_->stop();
    api_->shutdown();
    loop_.join();
  }
  uint16_t port() const { return api_->port(); }

 private:
  std::unique_ptr<sim::Simulation> sim_;
  objects::ObjectSet objects_;
  std::unique_ptr<RadioOps> ops_;
  std::unique_ptr<sim::Runner> runner_;
  std::unique_ptr<ApiServer> api_;
  std::thread loop_;
};

}  // namespace uavsim::server::api::testing
