// What the server says while it runs: one line per meaningful event (MAVLink client connected or left,
// armed, disarmed, mode change, take-off, touchdown, crash, failsafe and other critical messages, faults,
// mission events) on the console unless --quiet, the same events as JSON lines in --log-dir's
// events.jsonl, and a summary at exit. Loop thread only (the endpoint's hooks and the control observer
// both run there).
#pragma once

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <ostream>
#include <string>

#include "sim/simulation.hpp"
#include "uavsim/common/record_file.hpp"

namespace uavsim::server::app {

// One reported event. vehicle is -1 for events of the world or the server.
struct ReportedEvent {
  double time_s = 0.0;
  int vehicle = -1;
  std::string kind;    // "client_connected", "armed", "mode", "crash", "failsafe", ...
  std::string detail;  // the peer address, the mode's name, the crash's reason, the message, ...
};

// The console line of an event: "t=12.350 uav0: mode GUIDED". Thread-safe (pure).
std::string console_line(const ReportedEvent& event, const std::string& vehicle_name);
// The JSON line of an event (no newline): {"t":12.35,"vehicle":0,"name":"uav0","event":"mode",...}.
// Thread-safe (pure).
std::string json_line(const ReportedEvent& event, const std::string& vehicle_name);

class RunReporter {
 public:
  // console: null for --quiet; json: null without --log-dir. Both must outlive the reporter. Each
  // event's JSON line goes to json with one write(2) as it is reported, so a server killed at any
  // moment leaves every event reported so far in the file, whole. A failed write (disk full) is said
  // once on errors (may be null) and ends the file there; the run goes on.
  RunReporter(sim::Simulation& sim, std::ostream* console, common::RecordFile* json,
              std::ostream* errors = nullptr);

  // Reports the simulation's events recorded since the last call. Loop thread only.
  void on_control_step();
  // A MAVLink client connected to or left a vehicle's endpoint (peer: "tcp:ADDR:PORT", "udp:..."). Loop
  // thread only.
  void on_client(std::size_t vehicle, bool connected, const std::string& peer);
  // A flight controller's status text: severities up to 3 (error) are reported, failsafes as "failsafe".
  // Loop thread only.
  void on_status_text(std::size_t vehicle, int severity, const std::string& text);

  // Counts so far, for the summary.
  std::uint64_t crashes() const { return crashes_; }
  std::uint64_t failsafes() const { return failsafes_; }
  // The last few failsafes reported, oldest first (the recording's overlay shows them). Loop thread only.
  const std::deque<ReportedEvent>& recent_failsafes() const { return recent_failsafes_; }

  // The summary line(s) at exit: sim and wall time, real-time factor, vehicles, crashes, failsafes,
  // clients. extra is appended (e.g. the MAVLink frame counts). Loop thread only.
  void print_summary(std::ostream& out, const std::string& extra) const;

 private:
  void report(const ReportedEvent& event);

  sim::Simulation& sim_;
  std::ostream* console_;
  common::RecordFile* json_;
  std::ostream* errors_;
  bool json_failed_ = false;  // said once
  std::uint64_t next_event_ = 0;  // the seq of the next event to report
  std::uint64_t clients_connected_ = 0;
  std::uint64_t crashes_ = 0;
  std::uint64_t failsafes_ = 0;
  static constexpr std::size_t kRecentFailsafes = 8;
  std::deque<ReportedEvent> recent_failsafes_;
  std::chrono::steady_clock::time_point started_ = std::chrono::steady_clock::now();
};

}  // namespace uavsim::server::app
