// Flight-controller parameters from outside the code: ArduPilot parameter files (--defaults FILE.parm,
// the format Mission Planner, MAVProxy and QGroundControl save), the world's per-vehicle parameters, and
// the parameter table of the documentation (docs/parameters.md is --list-params' output).
#pragma once

#include <string>
#include <utility>
#include <vector>

namespace uavsim::server::app {

// One "NAME VALUE" with where it came from ("file.parm:12", "world uavsim:params:uav0").
struct ParamAssignment {
  std::string name;
  double value = 0.0;
  std::string where;
};

// Parses parameter-file text: one "NAME VALUE", "NAME,VALUE" or "NAME<TAB>VALUE" per entry, entries
// separated by newlines or ';', '#' starts a comment, blank entries are skipped. Checks each name and
// value against the flight controller's table. Throws std::invalid_argument "source:N: why" (N: the
// entry's line, or its position for ';'-separated text). Thread-safe (pure).
std::vector<ParamAssignment> parse_param_text(const std::string& text, const std::string& source);
// Reads and parses a parameter file; throws std::invalid_argument naming the file. Thread-safe.
std::vector<ParamAssignment> read_param_file(const std::string& path);

// Parameters per vehicle: the world's texts (uavsim:params:* for every vehicle, then
// uavsim:params:VEHICLE_NAME), then the files in order. world_texts are (text name, data) pairs.
// Throws std::invalid_argument for a bad entry or a text naming no vehicle of the world.
std::vector<std::vector<std::pair<std::string, double>>> vehicle_params(
    const std::vector<std::string>& vehicle_names,
    const std::vector<std::pair<std::string, std::string>>& world_texts,
    const std::vector<std::string>& files);

// The parameter table in Markdown: name, default, range, units and meaning (docs/parameters.md).
std::string params_markdown();

}  // namespace uavsim::server::app
