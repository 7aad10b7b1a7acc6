// Launcher: what a mission launcher (mbzirc2017-run, mbzirc2020-run, coverage-run) does around its
// mission: start uavsim-server on ephemeral ports (learnt from its banner) and connect a
// SimConnection to its API, spawn the mission programs with stdout and stderr read line by line
// (printed prefixed with the program's name unless quiet), put them on the lockstep clock, and stop
// and reap them all.
//
// Process tree: the server and every program start in one process group of their own (the first
// one's pid is its id: process_group()), stdin /dev/null, and with the kernel's parent-death signal
// set to SIGKILL, so a launcher killed in any way (SIGKILL, OOM, a timeout) takes them all with it:
// no server or agent outlives its run. A sweep may also kill the whole group at once. Ctrl-C in a
// terminal reaches only the launcher, which stops the others in order.
//
// Run records: when a program ends, the launcher names it, how (exit code, or the signal, with
// "out of memory?" when the kernel's OOM killer counts a kill in this cgroup or its log names the
// pid) and the sim time it last knew (note_sim_time, the ground-truth ticks); keep_summary()'s file
// holds that too, rewritten atomically as the run goes ("complete": false until write_summary()).
//
// Thread contract: a Launcher belongs to the thread that made it (its owner thread; its api() too);
// nothing here is thread-safe. The owner thread must outlive the programs it started: the kernel's
// parent-death signal follows the thread that forked, not the process.
#pragma once

#include <sys/types.h>

#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "uavsim/client/result.hpp"
#include "uavsim/client/sim_connection.hpp"

namespace uavsim::launch {

using client::Result;

// How to start the server: its program, the world, and options beside the launcher's own
// (--rate 0 --mavlink-port 0 --api-port 0 --lockstep-timeout 120).
struct ServerSpec {
  std::string path;
  std::string world;
  std::vector<std::string> extra_args;
  double start_timeout_s = 60.0;  // wall seconds for the banner and the API's hello
};

// The default run directory of a launcher: "runs/MISSION-seedN-YYYYMMDD-HHMMSS" (UTC). Thread-safe.
std::string default_run_dir(const std::string& mission, uint64_t seed);
// Makes dir (and its parents) and checks that a file can be written in it and that the file system
// has kMinRunDirFreeBytes free; false with a message that names the directory and the reason
// otherwise (a parent that is a file, a read-only or full file system). Thread-safe.
inline constexpr std::uint64_t kMinRunDirFreeBytes = 1 << 20;
bool make_run_dir(const std::string& dir, std::string* why);

// Where a launcher's run goes: its run directory ("" for none), the video ("" for none) and the
// summary JSON ("" for none).
struct RunFiles {
  std::string dir;
  std::string video;
  std::string summary;
};
// The run files from a launcher's options, the run directory made: run_dir_option "" or "auto"
// (the default) is default_run_dir(mission, seed), "none" (--no-run-dir) no directory, anything
// else that directory. video and summary are --record and --json as given; empty, they go into the
// run directory (video.mp4, summary.json) if there is one. record false (--no-record): no video.
// Fails (kIo) when the directory cannot be made. Thread-safe.
Result<RunFiles> resolve_run_files(const std::string& mission, uint64_t seed,
                                   const std::string& run_dir_option, const std::string& video,
                                   const std::string& summary, bool record);

// The program `name` in the directory of the running executable (/proc/self/exe). Thread-safe.
std::string sibling_program(const std::string& name);

// How a program of the launcher's ended.
struct ProgramEnd {
  std::string name;
  pid_t pid = -1;
  std::optional<int> exit_code;  // it exited (0: normally)
  std::optional<int> signal;     // it was killed by this signal
  bool stopped = false;          // the launcher stopped it (stop_all): an ordinary end
  bool out_of_memory = false;    // the kernel's OOM killer counted a kill when it died
  double sim_time_s = -1.0;      // the launcher's last known sim time; -1 before any
  // "killed by SIGKILL at sim t=53.20 s", "exited with code 1 at sim t=...", "exited normally ..."
  std::string how;
  // An end the run did not ask for: a signal the launcher did not send, or a non-zero exit code.
  bool abnormal() const { return !stopped && (signal.has_value() || exit_code.value_or(0) != 0); }
  nlohmann::json to_json() const;
};

// The exit codes every mission launcher uses (docs/missions.md, "When a run is killed").
inline constexpr int kExitSuccess = 0;        // the mission's goal was met
inline constexpr int kExitFellShort = 1;      // the run went to its end; the mission fell short
inline constexpr int kExitUsage = 2;          // bad options, or the run directory cannot be used
inline constexpr int kExitHarness = 4;        // the harness failed: the server died, the API failed
inline constexpr int kExitInterrupted = 130;  // SIGINT or SIGTERM stopped the run

// Ctrl-C in a terminal and a scheduler's SIGTERM: from this call on SIGINT and SIGTERM no longer
// end the launcher at once but set what interrupted() reads, so the run loop ends at its next turn
// and everything is stopped in order: the programs, then the server (which closes its logs), then
// the summary, written with "interrupted": true and the interruption as its cause (unless a program
// had already ended abnormally), and the exit code kExitInterrupted. A Launcher's waits
// (start_server, wait_lockstep_clients) end early with Error::kCancelled once it is set.
// Call once in main() before the launcher starts anything. Not thread-safe (it sets the process's
// signal dispositions); the handler itself is async-signal-safe.
void catch_interrupts();
// The signal (SIGINT or SIGTERM) that interrupted the run since catch_interrupts(); 0 while none
// has. Thread-safe.
int interrupted();
// The launcher's exit code at the end of a run: kExitInterrupted once interrupted() (whatever
// failed while it stopped), else kExitHarness when harness_failed, else kExitSuccess or
// kExitFellShort. Thread-safe.
int run_exit_code(bool harness_failed, bool success);

class Launcher {
 public:
  // Sim seconds between two rewrites of keep_summary()'s file.
  static constexpr double kSummaryPeriod_s = 10.0;

  // name prefixes the launcher's own messages; quiet: say() and the children's lines print nothing.
  // The calling thread becomes the owner thread.
  Launcher(std::string name, bool quiet);
  // Stops whatever still runs (stop_all(5)).
  // Owner thread only.
  ~Launcher();
  Launcher(const Launcher&) = delete;
  Launcher& operator=(const Launcher&) = delete;

  // Starts the server (child "server") as fast as possible on ephemeral ports, reads its banner
  // until the API's port and connects api() to it. Fails when the program cannot start, exits, or
  // prints no API port within spec.start_timeout_s, or the API does not answer.
  // Owner thread only.
  Result<void> start_server(const ServerSpec& spec);
  // The connection to the server's API; only after start_server() succeeded.
  // Owner thread only.
  client::SimConnection& api();
  // The API's TCP port (0 before start_server()).
  // Owner thread only.
  int api_port() const;
  // The TCP MAVLink port the server printed for this vehicle name; 0 if none.
  // Owner thread only.
  int mavlink_port(const std::string& vehicle) const;

  // Starts a program (argv[0] is its path) named `name` in the output, with this environment plus
  // env ("KEY=value"; an inherited UAVSIM_LOCKSTEP is dropped). Fails when it cannot be started.
  // Owner thread only.
  Result<void> spawn(const std::string& name, const std::vector<std::string>& argv,
                     const std::vector<std::string>& env = {});
  // "UAVSIM_LOCKSTEP=127.0.0.1:PORT/PERIOD": puts a client_cpp program on the server's lockstep.
  // Owner thread only.
  std::string lockstep_env(double period_s) const;
  // Waits (reading the children's output) until at least n clients have joined the lockstep.
  // Owner thread only.
  Result<void> wait_lockstep_clients(int n, double timeout_s);

  // Ground truth for the run directory: from the moment wait_lockstep_clients() has seen the
  // mission's clients, a connection of the launcher's own joins the lockstep with period 1 /
  // rate_hz (so it is not counted among them) and at each of its ticks writes one row per vehicle
  // into dir/truth_NAME.csv (t_s, position and velocity ENU, roll/pitch/yaw, battery, mode, armed,
  // crashed, on_ground) from the `vehicles` query; pump() answers the ticks. Call before
  // wait_lockstep_clients(); dir must exist.
  // Owner thread only.
  void record_truth(const std::string& dir, double rate_hz);
  // Rows written so far by record_truth (all vehicles).
  // Owner thread only.
  std::uint64_t truth_rows() const;

  // Every complete output line of a child (name, line without '\n') is given to cb, in order, after
  // it is printed. Callbacks add up; they may call this launcher's api(), not pump().
  // Owner thread only.
  void on_line(std::function<void(const std::string& child, const std::string& line)> cb);
  // Waits up to timeout_ms for output or API messages, then reads the children's lines (printed
  // "[name] line" unless quiet, then given to on_line) and what the API has sent (queued or given
  // to its handlers, as SimConnection::poll).
  // Owner thread only.
  void pump(int timeout_ms);
  // Prints a line unless quiet.
  // Owner thread only.
  void say(const std::string& line) const;
  // Wall seconds since the launcher was made.
  // Owner thread only.
  double wall_s() const;
  // True when every program spawned (the server aside, and the one named `except` if given: a
  // program that runs until stopped, like a ground station) has exited and its output is read.
  // Owner thread only.
  bool programs_done(const std::string& except = "");
  // True when the server has exited (or was never started).
  // Owner thread only.
  bool server_exited();
  // Stops the programs (SIGTERM, then SIGKILL after at most 5 s), then the server (SIGTERM: it
  // finishes a recording; SIGKILL after timeout_s), reaps them and prints their last lines.
  // Owner thread only.
  void stop_all(double timeout_s);

  // The process group of the server and the programs (0 before the first start).
  // Owner thread only.
  pid_t process_group() const;
  // The run's sim time as the mission's loop learns it; the ends of programs are stamped with the
  // latest, and keep_summary()'s file is rewritten every kSummaryPeriod_s of it.
  // Owner thread only.
  void note_sim_time(double t_s);
  // When a program ends (noticed by pump(), programs_done(), server_exited() or stop_all()), cb
  // gets how, after the launcher said it: an abnormal end on stderr always ("coverage-run: agent3
  // (pid 812) killed by SIGKILL at sim t=53.20 s"), an ordinary one as say(). cb may call api(),
  // not pump(). Callbacks add up. Owner thread only.
  void on_exit(std::function<void(const ProgramEnd&)> cb);
  // How the program `name` ended; nullopt while it runs (or if there is none).
  // Owner thread only.
  std::optional<ProgramEnd> ended(const std::string& name) const;
  // "the server was killed by SIGKILL at sim t=53.20 s" when the server ended, else "the server
  // exited": for the mission's harness-failure message. Owner thread only.
  std::string server_end() const;
  // "" while every record of the run is written; else the first that could not be (a full disk,
  // the file size limit), noticed by pump() and the waits: the launcher's ground truth, or the
  // server's event log or a tlog as the server says, "PATH: File too large at sim t=72.40 s". A
  // mission ends its run then, as a harness failure: the summary names it ("records_error", and
  // as the cause unless a program had ended abnormally before). Owner thread only.
  const std::string& records_error() const;

  // From now on path ("" for none) holds the run's summary so far: `partial` plus "complete":
  // false, sim_time_s, wall_time_s, "programs" (each one's end, or running), "interrupted" and
  // "records_error" (records_error(), null if none) and "cause" (among the ends noticed before an
  // interruption, the first program killed by a signal the launcher did not send, else the first
  // abnormal end; else a record that could not be written; else the interruption, "the launcher
  // was interrupted by SIGINT at sim t=..."; else the first abnormal end; null if none), replaced
  // atomically (temp file, fsync, rename) every kSummaryPeriod_s of
  // sim time and whenever a program ends, so a run killed at any moment leaves a summary.
  // Owner thread only.
  void keep_summary(const std::string& path, nlohmann::json partial);
  // Fields of the summary so far that keep_summary()'s next rewrite carries (merged over partial).
  // Owner thread only.
  void update_summary(const nlohmann::json& fields);
  // The final summary: `summary` plus "complete": true, "programs" and "cause", replaced atomically
  // at path. False when it cannot be written (the reason on stderr). Owner thread only.
  bool write_summary(const std::string& path, nlohmann::json summary);

 private:
  void start_truth();
  void check_children();
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace uavsim::launch
