// Telemetry logs in the format MAVProxy, QGroundControl and Mission Planner write and MAVExplorer reads
// (.tlog): each MAVLink frame as it went over the link, preceded by a big-endian 64-bit count of
// microseconds (UNIX time in those tools; sim time here, so a log of a run is the same in every run).
#pragma once

#include <cstddef>
#include <cstdint>
#include <fstream>
#include <span>
#include <string>
#include <vector>

namespace uavsim::server::mavlink {

// Length of the MAVLink frame at the start of bytes (v1 or v2, signed or not, from its header); 0 when
// bytes do not start with a frame's start byte or hold fewer than 3 bytes. Thread-safe (pure).
std::size_t frame_length(std::span<const std::uint8_t> bytes);

class TlogWriter {
 public:
  // Creates (truncates) path. Throws std::runtime_error naming the path if it cannot.
  explicit TlogWriter(const std::string& path);
  // Appends one frame stamped t_s seconds. Stamps never go backwards: after the sim clock restarts (a
  // reset) they continue from the last one. Buffered; one thread at a time.
  void write(double t_s, std::span<const std::uint8_t> frame);
  // Writes the buffered bytes to the file.
  void flush();
  std::uint64_t frames() const { return frames_; }
  const std::string& path() const { return path_; }

 private:
  std::string path_;
  std::ofstream out_;
  std::uint64_t last_stamp_us_ = 0;
  std::uint64_t offset_us_ = 0;     // added to sim time once the clock restarted
  std::uint64_t frames_ = 0;
};

// One record of a tlog.
struct TlogRecord {
  std::uint64_t stamp_us = 0;
  std::vector<std::uint8_t> frame;
};

// Reads a whole tlog (what TlogWriter wrote); stops at the first record that is not a whole frame.
// Thread-safe.
std::vector<TlogRecord> read_tlog(const std::string& path);

}  // namespace uavsim::server::mavlink
