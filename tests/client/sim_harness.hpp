// An in-process uavsim server for client tests: world + objects + MAVLink endpoints + sim API on ephemeral
// loopback ports, its Runner on a thread of its own as fast as possible, started paused so that a lockstep
// client joins at t = 0 (then resume()): every run of a test starts from the same state.
// ApiClient: a blocking line-JSON client for ground truth (`vehicles`) and fault injection.
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
#include "objects/world_objects.hpp"
#include "physics/world.hpp"
#include "sim/runner.hpp"
#include "sim/simulation.hpp"

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
    s::mavlink::EndpointConfig ec;
    ec.base_port = 0;
    if (!vehicle0_udp.empty()) ec.udp = {std::move(vehicle0_udp)};
    mavlink_ = std::make_unique<s::mavlink::MavlinkServer>(*sim_, ec);
    runner_ = std::make_unique<s::sim::Runner>(*sim_, 0.0);
    s::api::ApiConfig ac;
    ac.port = 0;
    ac.start_paused = start_paused;
    ac.lockstep_timeout_s = 30.0;
    api_ = std::make_unique<s::api::ApiServer>(*sim_, runner_.get(), objects_, ac);
    hooks_ = std::make_unique<EndpointHooks>(*mavlink_);
    api_->set_link_control(hooks_.get());
    api_->set_seq_waiter(hooks_.get());
    runner_->set_control_gate(api_->gate());
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
  std::unique_ptr<uavsim::server::sim::Simulation> sim_;
  uavsim::server::objects::ObjectSet objects_;
  std::unique_ptr<uavsim::server::mavlink::MavlinkServer> mavlink_;
  std::unique_ptr<uavsim::server::sim::Runner> runner_;
  std::unique_ptr<EndpointHooks> hooks_;
  std::unique_ptr<uavsim::server::api::ApiServer> api_;
  std::thread loop_;
};

// Blocking request/reply client of the sim API (10 s wall timeout per reply).
class ApiClient {
 public:
  explicit ApiClient(int port) {
    fd_ = socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_port = htons(static_cast<uint16_t>(port));
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    EXPECT_EQ(::connect(fd_, reinterpret_cast<sockaddr*>(&a), sizeof(a)), 0);
    read_json();  // hello
  }
  ~ApiClient() { ::close(fd_); }
  Json request(Json j) {
    const std::string line = j.dump() + "\n";
    EXPECT_EQ(::send(fd_, line.data(), line.size(), MSG_NOSIGNAL), static_cast<ssize_t>(line.size()));
    for (;;) {
      Json r = read_json();
      if (r.is_null() || r.contains("ok")) return r;
    }
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
  Json read_json() {
    for (;;) {
      const auto nl = buf_.find('\n');
      if (nl != std::string::npos) {
        Json j = Json::parse(buf_.substr(0, nl), nullptr, false);
        buf_.erase(0, nl + 1);
        return j;
      }
      pollfd p{fd_, POLLIN, 0};
      if (poll(&p, 1, 10000) <= 0) return Json();
      char tmp[65536];
      const ssize_t n = recv(fd_, tmp, sizeof(tmp), 0);
      if (n <= 0) return Json();
      buf_.append(tmp, static_cast<std::size_t>(n));
    }
  }
  int fd_ = -1;
  std::string buf_;
};

}  // namespace uavsim::client::testing
