// Telemetry logs in the format MAVProxy, QGroundControl and Mission Planner write and MAVExplorer
// reads
// (.tlog): each MAVLink frame as it went over the link, preceded by a big-endian 64-bit count of
// microseconds (UNIX time in those tools; sim time here, so a log of a run is the same in every
// run).
//
// Kill-safe: records are gathered in memory and handed to the kernel whole (common::RecordFile)
// once they span kFlushSpan_s of sim time or kFlushBytes, so a server killed at any moment leaves
// every frame but those of the last 0.1 s of sim before its newest frame on the file, with no torn
// frame.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "uavsim/common/record_file.hpp"

namespace uavsim::server::mavlink {

// Length of the MAVLink frame at the start of bytes (v1 or v2, signed or not, from its header); 0
// when bytes do not start with a frame's start byte or hold fewer than 3 bytes. Thread-safe (pure).
std::size_t frame_length(std::span<const std::uint8_t> bytes);

class TlogWriter {
 public:
  // the bound on what a kill loses: the records of at most this much sim time, or this many bytes
  static constexpr double kFlushSpan_s = 0.1;
  static constexpr std::size_t kFlushBytes = 64 * 1024;

  // Creates (truncates) path. Throws std::runtime_error naming the path if it cannot.
  explicit TlogWriter(const std::string& path);
  // Writes what is buffered.
  ~TlogWriter();
  // Appends one frame stamped t_s seconds. Stamps never go backwards: after the sim clock restarts
  // (a reset) they continue from the last one. Buffered (see above); one thread at a time.
  void write(double t_s, std::span<const std::uint8_t> frame);
  // Writes the buffered records to the file. False once a write failed (disk full: error() says
  // why; the log ends there and later frames are counted, not written).
  bool flush();
  const std::string& error() const { return file_.error(); }
  std::uint64_t frames() const { return frames_; }
  const std::string& path() const { return path_; }

 private:
  std::string path_;
  common::RecordFile file_;
  std::string pending_;                 // whole records not yet written
  std::uint64_t pending_since_us_ = 0;  // the stamp of the first of them
  std::uint64_t last_stamp_us_ = 0;
  std::uint64_t offset_us_ = 0;  // added to sim time once the clock restarted
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
