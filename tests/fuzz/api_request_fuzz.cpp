// libFuzzer target for the sim API's request path: fuzz bytes are sent as request lines over a real
// loopback connection to an ApiServer on a live simulation; the loop side runs in this thread (the
// gate, then physics steps) until the reply to a sentinel request arrives, so every line has been
// parsed, handled and answered. A crash, a sanitizer finding, a reply that is not one JSON object per
// line, or a sentinel that never comes back (-timeout) is a finding.
#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>

#include "../support/loopback_tcp.hpp"
#include "api/api_server.hpp"
#include "objects/world_objects.hpp"
#include "physics/world.hpp"
#include "sim/simulation.hpp"

namespace uavsim::server {
namespace {

void check(bool ok) {
  if (!ok) __builtin_trap();
}

constexpr const char* kSentinel = "{\"op\":\"status\",\"id\":\"fuzz-sentinel\"}\n";
constexpr std::size_t kMaxLines = 16;

struct Harness {
  std::unique_ptr<sim::Simulation> sim;
  objects::ObjectSet objects;
  std::unique_ptr<api::ApiServer> api;
  sim::Runner::Gate gate;
  int fd = -1;
  std::string received;

  Harness() {
    physics::ComposeOptions o;
    o.models_dir = UAVSIM_MODELS_DIR;
    sim = std::make_unique<sim::Simulation>(
        physics::World::load(std::string(UAVSIM_MODELS_DIR) + "/worlds/mbzirc2020.xml", o), sim::SimConfig{});
    objects = objects::add_world_objects(*sim);
    api::ApiConfig config;
    config.port = 0;
    api = std::make_unique<api::ApiServer>(*sim, nullptr, objects, config);
    // the gate never holds here (pause, lockstep): each call serves what is queued and returns
    api->set_stop_check([] { return true; });
    gate = api->gate();
    api->start();
    fd = socket(AF_INET, SOCK_STREAM, 0);
    check(uavsim::testing::connect_loopback_tcp(fd, api->port()));
    read_until_line_with("\"hello\"");
  }

  void send_all(const std::string& text) {
    std::size_t off = 0;
    while (off < text.size()) {
      const ssize_t n = ::send(fd, text.data() + off, text.size() - off, MSG_NOSIGNAL);
      check(n > 0);
      off += static_cast<std::size_t>(n);
    }
  }

  // runs the loop side and reads replies until a line containing marker; every line must be JSON
  void read_until_line_with(const std::string& marker) {
    for (;;) {
      for (std::size_t nl; (nl = received.find('\n')) != std::string::npos;) {
        const std::string line = received.substr(0, nl);
        received.erase(0, nl + 1);
        const nlohmann::json j = nlohmann::json::parse(line, nullptr, false);
        check(j.is_object());
        if (line.find(marker) != std::string::npos) return;
      }
      gate(sim->time_s());
      sim->step();
      pollfd p{fd, POLLIN, 0};
      if (poll(&p, 1, 1) <= 0) continue;
      char buf[65536];
      const ssize_t n = recv(fd, buf, sizeof(buf), 0);
      check(n > 0);  // the server never closes a well-behaved connection
      received.append(buf, static_cast<std::size_t>(n));
    }
  }
};

}  // namespace
}  // namespace uavsim::server

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace uavsim::server;
  static Harness h;
  // at most kMaxLines lines; each ends with a newline (so none joins the sentinel)
  std::string text(reinterpret_cast<const char*>(data), size);
  std::size_t lines = 0;
  for (std::size_t i = 0; i < text.size(); ++i) {
    if (text[i] == '\n' && ++lines >= kMaxLines) text.resize(i + 1);
  }
  if (!text.empty() && text.back() != '\n') text += '\n';
  h.send_all(text + kSentinel);
  h.read_until_line_with("fuzz-sentinel");
  return 0;
}
