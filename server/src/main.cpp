// uavsim-server: simulates a world of multirotors (see --help).
#include <csignal>
#include <iostream>

#include "app/options.hpp"
#include "app/server_app.hpp"

int main(int argc, char** argv) {
  int exit_code = 0;
  const auto options = uavsim::server::app::parse_options(argc, argv, &exit_code);
  if (!options) return exit_code;
  std::signal(SIGINT, [](int) { uavsim::server::app::stop_server(); });
  std::signal(SIGTERM, [](int) { uavsim::server::app::stop_server(); });
  try {
    return uavsim::server::app::run_server(*options);
  } catch (const std::exception& e) {
    std::cerr << "uavsim-server: " << e.what() << "\n";
    return 1;
  }
}
