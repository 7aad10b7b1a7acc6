// uavsim-server: simulates a world of multirotors (see --help).
#include <csignal>
#include <cstdlib>
#include <iostream>
#include <string>
#include <vector>

#include "app/options.hpp"
#include "app/server_app.hpp"

int main(int argc, char** argv) {
  const std::vector<std::string> args(argv + 1, argv + argc);
  const auto parsed = uavsim::server::app::parse_args(args, [](const std::string& name) -> std::optional<std::string> {
    const char* v = std::getenv(name.c_str());
    if (v == nullptr) return std::nullopt;
    return std::string(v);
  });
  if (!parsed.options) {
    if (!parsed.error.empty()) std::cerr << "uavsim-server: " << parsed.error << "\n";
    std::cout << parsed.output;
    return parsed.exit_code;
  }
  std::signal(SIGINT, [](int sig) { uavsim::server::app::stop_server(sig); });
  std::signal(SIGTERM, [](int sig) { uavsim::server::app::stop_server(sig); });
  try {
    return uavsim::server::app::run_server(*parsed.options);
  } catch (const std::exception& e) {
    std::cerr << "uavsim-server: " << e.what() << "\n";
    return 1;
  }
}
