// What every mission program (a vehicle's, a ground station's) sets up first: an event loop on the
// run's clock (the server's lockstep under UAVSIM_LOCKSTEP, else the wall clock), log lines stamped
// with the loop's time, "NAME t=12.35 text", which the mission launchers read from stdout, and a
// vehicle's MAVLink link.
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <string>

#include "uavsim/client/event_loop.hpp"
#include "uavsim/client/vehicle.hpp"
#include "uavsim/mission/flight_command.hpp"

namespace uavsim::mission {

// Thread contract: loop thread only (the thread that created it).
class ProgramLoop {
 public:
  // The loop, or nullptr after "NAME: event loop: why" on stderr.
  static std::unique_ptr<ProgramLoop> create(std::string name);

  client::EventLoop& loop() { return *loop_; }
  const std::string& name() const { return name_; }
  // "NAME t=SECONDS line" on stdout, flushed at once: the launcher reads the lines as they come.
  void log(const std::string& line) const;
  // The loop's time in whole microseconds (a GcsLink's clock).
  int64_t now_us() const;

 private:
  ProgramLoop(std::string name, std::unique_ptr<client::EventLoop> loop)
      : name_(std::move(name)), loop_(std::move(loop)) {}
  std::string name_;
  std::unique_ptr<client::EventLoop> loop_;
};

// The link to the simulated vehicle `vehicle` over MAVLink at `mavlink` (tcp:HOST:PORT), with the
// 20 Hz telemetry the missions fly on, connected within 30 s; nullptr after logging "connect: why".
std::unique_ptr<client::Vehicle> connect_vehicle(ProgramLoop& program, const std::string& vehicle,
                                                 const std::string& mavlink);

// The command-line options every vehicle program takes; a program's own Options derive from it.
struct VehicleProgramOptions {
  std::string mavlink;    // --mavlink tcp:HOST:PORT
  std::string vehicle;    // --vehicle NAME: the simulated vehicle
  std::string camera;     // --camera NAME
  std::string video_log;  // --video-log FILE.vlog ("" none)
};

// The option `name` with its `value` into o when it is one of VehicleProgramOptions'; false when
// it is not (the program's own, or unknown). Thread-safe.
bool parse_vehicle_program_option(const std::string& name, const char* value,
                                  VehicleProgramOptions* o);

// What a vehicle program (mbzirc2017-uav, mbzirc2020-uav) sets up first: its loop, named after the
// vehicle, and its link to the vehicle.
struct VehicleProgram {
  std::unique_ptr<ProgramLoop> program;
  std::unique_ptr<client::Vehicle> vehicle;
};

// The loop of the program for the simulated vehicle `vehicle` and that vehicle's link (as
// connect_vehicle); nullopt after the loop's error on stderr or "connect: why" in the log.
// Loop thread only (the calling thread becomes it).
std::optional<VehicleProgram> start_vehicle_program(const std::string& vehicle,
                                                    const std::string& mavlink);

// Waits up to timeout_s for the vehicle to be ready to fly (client::Vehicle::wait_ready); false
// after "wait ready: why" in the log.
bool wait_vehicle_ready(const ProgramLoop& program, client::Vehicle& uav, double timeout_s);

// The missions' take-off: GUIDED, armed, climbing to altitude_m above the ground, without waiting
// for it (the mission's state machine watches the climb). The first refusal's error.
client::Result<void> take_off_guided(client::Vehicle& uav, double altitude_m);

// Carries out the state machine's command on the vehicle: take_off_guided, the velocity setpoint
// with the heading yaw_enu_rad, or all motors off at once (MAV_CMD_COMPONENT_ARM_DISARM forced). A
// refusal goes to the log as "take-off: why", "velocity: why" or "force disarm: why"; a refused
// velocity only when log_velocity_refusal (a failed vehicle's setpoints are refused by design).
// Loop thread only.
void fly(const ProgramLoop& program, client::Vehicle& uav, const FlightCommand& command,
         double yaw_enu_rad, bool log_velocity_refusal = true);

}  // namespace uavsim::mission
