// uavsim-server as a function: load the world, build the simulation and its endpoints, run the clock.
#pragma once

#include "app/options.hpp"

namespace uavsim::server::app {

// Runs the server until the duration, the demo's end or stop_server(). Returns the process exit code.
// Startup errors (bad world, bad option) are printed with the file and line and return 1.
int run_server(const Options& options);

// Asks a running server to stop (from a signal handler: only sets an atomic flag).
void stop_server();

}  // namespace uavsim::server::app
