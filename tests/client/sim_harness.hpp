// An in-process uavsim server for client tests: world + objects + MAVLink endpoints + sim API on ephemeral
// loopback ports, sharing one network I/O loop as in uavsim-server, its Runner on a thread of its own as fast as possible, started paused so that a lockstep
// client joins at t = 0 (then resume()): every run of a test starts from the same state.
// ApiClient: a blocking client (SimConnection) for ground truth (`vehicles`) and fault injection.
#pragma once

#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <gtest/gtest.h>

#include <limits>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include <Eigen/Core>
#include <nlohmann/json.hpp>

#include "api/api_server.hpp"
#include "app/endpoint_hooks.hpp"
#include "mavlink/endpoint.hpp"
#include "net/event_loop.hpp"
#include "objects/world_objects.hpp"
#include "physics/world.hpp"
#include "sim/runner.hpp"
#include "sim/simulation.hpp"
#include "uavsim/client/sim_connection.hpp"

namespace uavsim::client::testing {

using Json = nlohmann::json;

class SimServer {
 public:
  // vehicle0_udp: UDP links of vehicle 0 beside its TCP endpoint (--out)
  explicit SimServer(const std::string& world = "empty.xml", bool start_paused = true,
                     std::vector<uavsim::server::mavlink::UdpEndpoint> vehicle0_udp = {}) {
    namespace s = uavsim::server;
    s::physics::ComposeOptions o;
    o.models_dir = UAVSIM_MODELS_DIR;
    sim_ = std::make_unique<s::sim::Simulation>(
        s::physics::World::load(std::string(UAVSIM_MODELS_DIR) + "/worlds/" + world, o), s::sim::SimConfig{});
    objects_ = s::objects::add_world_objects(*sim_);
    io_loop_.start();
    s::mavlink::EndpointConfig ec;
    ec.base_port = 0;
    if (!vehicle0_udp.empty()) ec.udp = {std::move(vehicle0_udp)};
    mavlink_ = std::make_unique<s::mavlink::MavlinkServer>(*sim_, ec, &io_loop_);
    mavlink_->schedule(sim_->schedule());
    runner_ = std::make_unique<s::sim::Runner>(*sim_, 0.0);
    s::api::ApiConfig ac;
    ac.port = 0;
    ac.start_paused = start_paused;
    ac.lockstep_timeout_s = 30.0;
    ac.io_loop = &io_loop_;
    api_ = std::make_unique<s::api::ApiServer>(*sim_, runner_.get(), objects_, ac);
    hooks_ = std::make_unique<EndpointHooks>(*mavlink_);
    api_->set_link_control(hooks_.get());
    api_->set_seq_waiter(hooks_.get());
    runner_->add_gate(s::sim::Phase::kQueuedTasks, "api", api_->gate());
    api_->start();
    loop_ = std::thread([this] { runner_->run_until(std::numeric_limits<double>::infinity()); });
  }
  ~SimServer() {
    runner_->stop();
    api_->shutdown();
    loop_.join();
    mavlink_.reset();
  }
  int api_port() const { return api_->port(); }
  // wake-ups the server has written for the shared-memory streams, all of them together
  uint64_t shm_wakeups() const { return api_->shm_transport().wakeups_total(); }
  std::string mavlink_address(std::size_t vehicle = 0) const {
    return "tcp:127.0.0.1:" + std::to_string(mavlink_->port(vehicle));
  }
  std::size_t mavlink_clients(std::size_t vehicle = 0) const { return mavlink_->client_count(vehicle); }
  // the local port of vehicle 0's k-th UDP link
  int udp_port(std::size_t k = 0) const { return mavlink_->udp_port(0, k); }
  uavsim::server::mavlink::EndpointStats mavlink_stats(std::size_t vehicle = 0) const {
    return mavlink_->stats(vehicle);
  }

 private:
  // the endpoint's hooks as uavsim-server wires them: commands sent before `done` take effect at that
  // tick, and telemetry queued before a tick reaches the client before the tick
  using EndpointHooks = uavsim::server::app::EndpointHooks;
  uavsim::server::net::EventLoop io_loop_;  // first: outlives the servers it serves
  std::unique_ptr<uavsim::server::sim::Simulation> sim_;
  uavsim::server::objects::ObjectSet objects_;
  std::unique_ptr<uavsim::server::mavlink::MavlinkServer> mavlink_;
  std::unique_ptr<uavsim::server::sim::Runner> runner_;
  std::unique_ptr<EndpointHooks> hooks_;
  std::unique_ptr<uavsim::server::api::ApiServer> api_;
  std::thread loop_;
};

// Blocking request/reply client of the sim API (10 s wall timeout per reply), on SimConnection: a reply as
// the wire has it ({"ok": true, "result": ...} or {"ok": false, "error": {"message": ...}}), null when
// the connection failed.
class ApiClient {
 public:
  explicit ApiClient(int port) {
    auto c = SimConnection::connect("127.0.0.1", static_cast<uint16_t>(port), 10.0);
    EXPECT_TRUE(c) << c.message();
    if (c) conn_ = std::move(*c);
  }
  Json request(Json j) {
    if (conn_ == nullptr) return Json();
    const auto r = conn_->request(std::move(j), 10.0);
    if (r) return Json{{"ok", true}, {"result", *r}};
    if (r.code() == Error::kTimeout || !conn_->connected()) return Json();
    return Json{{"ok", false}, {"error", {{"message", r.message()}}}};
  }
  // ground truth of a vehicle: the `vehicles` entry
  Json truth(int vehicle = 0) {
    const Json r = request({{"op", "vehicles"}});
    if (!r.is_object() || r.value("ok", false) != true) return Json();
    return r["result"]["vehicles"][vehicle];
  }
  Eigen::Vector3d truth_position_enu(int vehicle = 0) {
    const Json t = truth(vehicle);
    if (t.is_null()) return Eigen::Vector3d::Constant(std::numeric_limits<double>::quiet_NaN());
    const auto p = t["position_enu_m"];
    return {p[0].get<double>(), p[1].get<double>(), p[2].get<double>()};
  }
  double sim_time() {
    const Json r = request({{"op", "status"}});
    return r.is_object() && r.value("ok", false) ? r["result"].value("time_s", -1.0) : -1.0;
  }

 private:
  std::unique_ptr<SimConnection> conn_;
};

}  // namespace uavsim::client::testing
