#include "uavsim/mission/program.hpp"

#include <cmath>
#include <cstdio>
#include <utility>

namespace uavsim::mission {

std::unique_ptr<ProgramLoop> ProgramLoop::create(std::string name) {
  auto created = client::EventLoop::create();
  if (!created) {
    std::fprintf(stderr, "%s: event loop: %s\n", name.c_str(), created.message().c_str());
    return nullptr;
  }
  return std::unique_ptr<ProgramLoop>(new ProgramLoop(std::move(name), std::move(*created)));
}

void ProgramLoop::log(const std::string& line) const {
  std::printf("%s t=%.2f %s\n", name_.c_str(), loop_->now(), line.c_str());
  std::fflush(stdout);
}

int64_t ProgramLoop::now_us() const {
  return static_cast<int64_t>(std::llround(loop_->now() * 1e6));
}

std::unique_ptr<client::Vehicle> connect_vehicle(ProgramLoop& program, const std::string& vehicle,
                                                 const std::string& mavlink) {
  client::VehicleConfig vc;
  vc.telemetry_rate_hz = 20.0;
  vc.sim_vehicle = vehicle;
  auto uav = std::make_unique<client::Vehicle>(program.loop(), vc);
  if (auto r = uav->connect(mavlink, 30); !r) {
    program.log("connect: " + r.message());
    return nullptr;
  }
  return uav;
}

bool parse_vehicle_program_option(const std::string& name, const char* value,
                                  VehicleProgramOptions* o) {
  for (auto [option, field] :
       {std::pair{"--mavlink", &o->mavlink}, std::pair{"--vehicle", &o->vehicle},
        std::pair{"--camera", &o->camera}, std::pair{"--video-log", &o->video_log}}) {
    if (name == option) {
      *field = value;
      return true;
    }
  }
  return false;
}

std::optional<VehicleProgram> start_vehicle_program(const std::string& vehicle,
                                                    const std::string& mavlink) {
  VehicleProgram p;
  p.program = ProgramLoop::create(vehicle);
  if (!p.program) return std::nullopt;
  p.vehicle = connect_vehicle(*p.program, vehicle, mavlink);
  if (!p.vehicle) return std::nullopt;
  return p;
}

bool wait_vehicle_ready(const ProgramLoop& program, client::Vehicle& uav, double timeout_s) {
  if (auto r = uav.wait_ready(timeout_s); !r) {
    program.log("wait ready: " + r.message());
    return false;
  }
  return true;
}

client::Result<void> take_off_guided(client::Vehicle& uav, double altitude_m) {
  auto r = uav.set_mode(client::FlightMode::kGuided);
  if (r) r = uav.arm();
  if (r) r = uav.takeoff(altitude_m, false);
  return r;
}

void fly(const ProgramLoop& program, client::Vehicle& uav, const FlightCommand& command,
         double yaw_enu_rad, bool log_velocity_refusal) {
  switch (command.action) {
    case FlightCommand::Action::kNone:
      break;
    case FlightCommand::Action::kArmAndTakeOff:
      if (auto r = take_off_guided(uav, command.takeoff_altitude_m); !r)
        program.log("take-off: " + r.message());
      break;
    case FlightCommand::Action::kVelocity:
      if (auto r = uav.set_velocity_enu_yaw(command.velocity_enu_m_s, yaw_enu_rad);
          !r && log_velocity_refusal) {
        program.log("velocity: " + r.message());
      }
      break;
    case FlightCommand::Action::kForceDisarm:
      // forced: the autopilot's land detector may not have agreed yet (the FSM saw the touchdown)
      if (auto r = uav.disarm(true); !r) program.log("force disarm: " + r.message());
      break;
  }
}

}  // namespace uavsim::mission
