// uavsim-server as a function: load the world, build the simulation and its endpoints, run the clock.
#pragma once

#include <string>
#include <vector>

#include "app/options.hpp"
#include "uavsim/common/geodesy.hpp"
#include "physics/world.hpp"

namespace uavsim::server::app {

// Runs the server until the duration, the demo's end or stop_server(). Returns the process exit code.
// Startup errors (bad world, bad option) are printed with the file and line and return 1.
int run_server(const Options& options);

// The world file to load: given itself when it is a file, else the shipped world of that name in
// models_dir/worlds ("mbzirc2020" or "mbzirc2020.xml"). Throws std::runtime_error listing the shipped worlds.
std::string resolve_world_path(const std::string& given, const std::string& models_dir);
// The names of the worlds in models_dir/worlds, sorted.
std::vector<std::string> shipped_worlds(const std::string& models_dir);
// What a world file holds, in one line: the first sentence of its leading <!-- comment -->, white
// space collapsed, cut at a word to at most max_chars (with "..."); "" when it has none.
std::string world_summary(const std::string& world_path, std::size_t max_chars = 80);
// --list-worlds: "# models: DIR (from)" then "NAME  SUMMARY" per shipped world. Thread-safe.
std::string list_worlds_text(const std::string& models_dir, const std::string& from);
// Warnings about options that expose the server (non-loopback --bind / --api-bind), one line each.
std::vector<std::string> option_warnings(const Options& options);

// The geodetic position of the world origin: --home, else the world's custom numeric uavsim:home
// (LAT LON ALT), else the default. Throws physics::WorldError for a malformed uavsim:home.
common::GeodeticOrigin world_home(const physics::World& world, const Options& options);

// Asks a running server to stop (from a signal handler: only sets an atomic flag).
void stop_server();
// The same, for a signal: if the loop has not stopped within the watchdog's grace time (5 s), the
// process exits with 128 + signal without it.
void stop_server(int signal);

}  // namespace uavsim::server::app
