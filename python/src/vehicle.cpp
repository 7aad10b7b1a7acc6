// uavsim._core: Vehicle (a MAVLink vehicle over TCP/UDP), its telemetry and missions.
#include "uavsim/client/vehicle.hpp"

#include <pybind11/eigen.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <cmath>
#include <limits>
#include <optional>
#include <string>

#include "bindings.hpp"

namespace uavsim::python {

namespace {

using client::FlightMode;
using client::MissionItem;
using client::Telemetry;
using client::Vehicle;
using client::VehicleConfig;

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// A vehicle on a loop; the Python object keeps the loop's object alive (keep_alive), so the loop
// outlives it.
struct PyVehicle : OnLoop<Vehicle> {
  PyVehicle() : OnLoop("vehicle") {}
  Vehicle& v() { return get(); }
  CallbackErrors& errors() { return *loop->errors; }
};

double positive(double v, const char* name) {
  if (!(std::isfinite(v) && v > 0.0)) {
    raise_failure({Error::kInvalidArgument,
                   std::string(name) + " must be finite and > 0, not " + std::to_string(v)});
  }
  return v;
}

// An optional angle from Python: None is "keep" (NaN for the library), a number must be finite.
double optional_angle(const std::optional<double>& a, const char* name) {
  if (!a) return kNaN;
  if (!std::isfinite(*a))
    raise_failure({Error::kInvalidArgument, std::string(name) + " must be finite or None"});
  return *a;
}

// done(None) on success, done(UavsimError) on failure, on the loop thread with the GIL
std::function<void(Result<void>)> python_done(PyVehicle& pv, std::optional<py::function> fn) {
  if (!fn) return {};
  return [errors = pv.loop->errors, f = hold_callable(std::move(*fn))](Result<void> r) {
    py::gil_scoped_acquire gil;
    errors->guard([&] {
      if (r.ok()) {
        (*f)(py::none());
        return;
      }
      try {
        raise_failure(r.error());
      } catch (py::error_already_set& e) {
        (*f)(e.value());
      }
    });
  };
}

}  // namespace

void bind_vehicle(py::module_& m) {
  py::enum_<FlightMode>(m, "FlightMode", "ArduCopter flight modes (custom_mode numbers).")
      .value("STABILIZE", FlightMode::kStabilize)
      .value("ACRO", FlightMode::kAcro)
      .value("ALT_HOLD", FlightMode::kAltHold)
      .value("AUTO", FlightMode::kAuto)
      .value("GUIDED", FlightMode::kGuided)
      .value("LOITER", FlightMode::kLoiter)
      .value("RTL", FlightMode::kRtl)
      .value("CIRCLE", FlightMode::kCircle)
      .value("LAND", FlightMode::kLand)
      .value("DRIFT", FlightMode::kDrift)
      .value("SPORT", FlightMode::kSport)
      .value("FLIP", FlightMode::kFlip)
      .value("AUTOTUNE", FlightMode::kAutotune)
      .value("POSHOLD", FlightMode::kPosHold)
      .value("BRAKE", FlightMode::kBrake)
      .value("THROW", FlightMode::kThrow)
      .value("AVOID_ADSB", FlightMode::kAvoidAdsb)
      .value("GUIDED_NOGPS", FlightMode::kGuidedNoGps)
      .value("SMART_RTL", FlightMode::kSmartRtl)
      .value("FLOWHOLD", FlightMode::kFlowHold)
      .value("FOLLOW", FlightMode::kFollow)
      .value("ZIGZAG", FlightMode::kZigZag)
      .value("SYSTEMID", FlightMode::kSystemId)
      .value("AUTOROTATE", FlightMode::kAutorotate)
      .value("AUTO_RTL", FlightMode::kAutoRtl)
      .value("TURTLE", FlightMode::kTurtle);
  py::enum_<client::LandedState>(m, "LandedState")
      .value("UNKNOWN", client::LandedState::kUnknown)
      .value("ON_GROUND", client::LandedState::kOnGround)
      .value("IN_AIR", client::LandedState::kInAir)
      .value("TAKEOFF", client::LandedState::kTakeoff)
      .value("LANDING", client::LandedState::kLanding);

  // the telemetry cache, read-only (vectors as numpy arrays; a copy of the vehicle's state at one
  // moment)
  py::class_<Telemetry> t(m, "Telemetry", "What the vehicle reported (MAVLink), at one moment.");
#define UAVSIM_RO(field) t.def_readonly(#field, &Telemetry::field)
  UAVSIM_RO(heartbeat_seen);
  UAVSIM_RO(last_heartbeat_time);
  UAVSIM_RO(sysid);
  UAVSIM_RO(mode);
  UAVSIM_RO(custom_mode);
  UAVSIM_RO(armed);
  UAVSIM_RO(system_status);
  UAVSIM_RO(landed);
  UAVSIM_RO(sensors_health);
  UAVSIM_RO(prearm_ok);
  UAVSIM_RO(ekf_flags);
  UAVSIM_RO(ekf_ok);
  UAVSIM_RO(vehicle_time_s);
  UAVSIM_RO(has_local_position);
  UAVSIM_RO(position_ned_m);
  UAVSIM_RO(velocity_ned_m_s);
  UAVSIM_RO(position_enu_m);
  UAVSIM_RO(velocity_enu_m_s);
  UAVSIM_RO(has_global_position);
  UAVSIM_RO(position);
  UAVSIM_RO(relative_alt_m);
  UAVSIM_RO(has_attitude);
  UAVSIM_RO(roll_rad);
  UAVSIM_RO(pitch_rad);
  UAVSIM_RO(yaw_rad);
  UAVSIM_RO(body_rates_rad_s);
  UAVSIM_RO(heading_deg);
  UAVSIM_RO(battery_voltage_v);
  UAVSIM_RO(battery_current_a);
  UAVSIM_RO(battery_remaining_pct);
  UAVSIM_RO(battery_consumed_mah);
  UAVSIM_RO(gps_fix_type);
  UAVSIM_RO(gps_satellites);
  UAVSIM_RO(gps_hdop);
  UAVSIM_RO(gps_position);
  UAVSIM_RO(home_set);
  UAVSIM_RO(home);
  UAVSIM_RO(home_ned_m);
  UAVSIM_RO(origin_set);
  UAVSIM_RO(origin);
  UAVSIM_RO(has_gimbal);
  UAVSIM_RO(gimbal_pitch_deg);
  UAVSIM_RO(gimbal_roll_deg);
  UAVSIM_RO(gimbal_yaw_deg);
  UAVSIM_RO(mission_current);
  UAVSIM_RO(mission_last_reached);
#undef UAVSIM_RO

  py::class_<MissionItem>(m, "MissionItem",
                          "One mission item (MISSION_ITEM_INT); item 0 (home) is added on upload.")
      .def(py::init<>())
      .def_readwrite("command", &MissionItem::command)
      .def_readwrite("frame", &MissionItem::frame)
      .def_readwrite("param1", &MissionItem::param1)
      .def_readwrite("param2", &MissionItem::param2)
      .def_readwrite("param3", &MissionItem::param3)
      .def_readwrite("param4", &MissionItem::param4)
      .def_readwrite("lat_deg", &MissionItem::lat_deg)
      .def_readwrite("lon_deg", &MissionItem::lon_deg)
      .def_readwrite("alt_m", &MissionItem::alt_m)
      .def_readwrite("autocontinue", &MissionItem::autocontinue)
      .def_static("takeoff", &MissionItem::takeoff, py::arg("rel_alt_m"))
      .def_static("waypoint", &MissionItem::waypoint, py::arg("lat_deg"), py::arg("lon_deg"),
                  py::arg("rel_alt_m"), py::arg("hold_s") = 0.0)
      .def_static("land", &MissionItem::land)
      .def_static("rtl", &MissionItem::rtl);

  py::class_<PyVehicle>(m, "Vehicle", R"(A proxy for one ArduCopter-compatible vehicle over MAVLink.

Blocking calls (connect, wait_ready, arm, takeoff, ...) run the loop while they wait, so timers, other
vehicles and callbacks carry on; under lockstep every timeout is sim time. Failures raise UavsimError
(the vehicle's refusal carries its MAV_RESULT in .mav_result).)")
      .def(py::init([](PyLoop& loop, int gcs_sysid, int gcs_compid, int target_sysid,
                       double heartbeat_period_s, double telemetry_rate_hz,
                       double command_timeout_s, int command_attempts, double setpoint_resend_s,
                       const std::string& sim_vehicle) {
             for (auto [v, name] :
                  {std::pair{gcs_sysid, "gcs_sysid"}, std::pair{gcs_compid, "gcs_compid"},
                   std::pair{target_sysid, "target_sysid"}}) {
               if (v < 0 || v > 255)
                 raise_failure({Error::kInvalidArgument, std::string(name) + " must be in 0..255"});
             }
             if (command_attempts < 1 || command_attempts > 100) {
               raise_failure({Error::kInvalidArgument, "command_attempts must be in 1..100"});
             }
             VehicleConfig c;
             c.gcs_sysid = static_cast<std::uint8_t>(gcs_sysid);
             c.gcs_compid = static_cast<std::uint8_t>(gcs_compid);
             c.target_sysid = static_cast<std::uint8_t>(target_sysid);
             c.heartbeat_period_s = positive(heartbeat_period_s, "heartbeat_period_s");
             c.telemetry_rate_hz = positive(telemetry_rate_hz, "telemetry_rate_hz");
             c.command_timeout_s = positive(command_timeout_s, "command_timeout_s");
             c.command_attempts = command_attempts;
             c.setpoint_resend_s = positive(setpoint_resend_s, "setpoint_resend_s");
             c.sim_vehicle = sim_vehicle;
             auto pv = std::make_unique<PyVehicle>();
             pv->hold(loop, std::make_unique<Vehicle>(loop.get(), c));
             return pv;
           }),
           py::arg("loop"), py::kw_only(), py::arg("gcs_sysid") = 255, py::arg("gcs_compid") = 190,
           py::arg("target_sysid") = 0, py::arg("heartbeat_period_s") = 1.0,
           py::arg("telemetry_rate_hz") = 10.0, py::arg("command_timeout_s") = 1.0,
           py::arg("command_attempts") = 3, py::arg("setpoint_resend_s") = 0.5,
           py::arg("sim_vehicle") = "", py::keep_alive<1, 2>())
      .def(
          "connect",
          [](PyVehicle& pv, const std::string& address, double timeout_s) {
            checked_duration(timeout_s, "timeout_s");
            blocking_result(pv.errors(),
                            [&, &v = pv.v()] { return v.connect(address, timeout_s); });
          },
          py::arg("address"), py::arg("timeout_s") = 10.0,
          "Connects to \"tcp:HOST:PORT\", \"udp:HOST:PORT\" or \"udpin:ADDR:PORT\" and waits for a "
          "heartbeat.")
      .def_static("address_from_env", &Vehicle::address_from_env,
                  py::arg("fallback") = "tcp:127.0.0.1:5760")
      .def("disconnect", [](PyVehicle& pv) { pv.v().disconnect(); })
      .def(
          "close", [](PyVehicle& pv) { pv.close(); },
          "Destroys the vehicle's C++ side now (its link closes); later calls raise "
          "ConnectionError.")
      .def_property_readonly("connected", [](PyVehicle& pv) { return pv.v().connected(); })
      .def(
          "wait_ready",
          [](PyVehicle& pv, double timeout_s) {
            checked_duration(timeout_s, "timeout_s");
            blocking_result(pv.errors(), [&, &v = pv.v()] { return v.wait_ready(timeout_s); });
          },
          py::arg("timeout_s") = 60.0,
          "Waits for heartbeat, home, a 3D GPS fix, a healthy EKF and pre-arm checks.")
      .def_property_readonly("ready", [](PyVehicle& pv) { return pv.v().ready(); })
      .def_property_readonly(
          "telemetry", [](PyVehicle& pv) { return pv.v().telemetry(); },
          "A copy of the telemetry now.")
      .def(
          "on_telemetry",
          [](PyVehicle& pv, std::optional<py::function> fn) {
            if (!fn) {
              pv.v().on_telemetry({});
              return;
            }
            pv.v().on_telemetry(
                [errors = pv.loop->errors, f = hold_callable(std::move(*fn))](const Telemetry& tm) {
                  py::gil_scoped_acquire gil;
                  errors->guard([&] { (*f)(tm); });
                });
          },
          py::arg("fn"),
          "fn(Telemetry) after every telemetry update, on the loop thread (None removes it).")
      .def(
          "on_status_text",
          [](PyVehicle& pv, std::optional<py::function> fn) {
            if (!fn) {
              pv.v().on_status_text({});
              return;
            }
            pv.v().on_status_text([errors = pv.loop->errors, f = hold_callable(std::move(*fn))](
                                      int severity, const std::string& text) {
              py::gil_scoped_acquire gil;
              errors->guard([&] { (*f)(severity, text); });
            });
          },
          py::arg("fn"), "fn(severity, text) for every STATUSTEXT (None removes it).")
      .def_property_readonly("status_texts", [](PyVehicle& pv) { return pv.v().status_texts(); })
      .def(
          "set_mode",
          [](PyVehicle& pv, FlightMode mode) {
            blocking_result(pv.errors(), [&, &v = pv.v()] { return v.set_mode(mode); });
          },
          py::arg("mode"))
      .def(
          "arm",
          [](PyVehicle& pv, bool force) {
            blocking_result(pv.errors(), [&, &v = pv.v()] { return v.arm(force); });
          },
          py::arg("force") = false)
      .def(
          "disarm",
          [](PyVehicle& pv, bool force) {
            blocking_result(pv.errors(), [&, &v = pv.v()] { return v.disarm(force); });
          },
          py::arg("force") = false)
      .def(
          "takeoff",
          [](PyVehicle& pv, double rel_alt_m, bool wait, double timeout_s) {
            checked_duration(timeout_s, "timeout_s");
            blocking_result(pv.errors(),
                            [&, &v = pv.v()] { return v.takeoff(rel_alt_m, wait, timeout_s); });
          },
          py::arg("rel_alt_m"), py::arg("wait") = true, py::arg("timeout_s") = 60.0,
          "NAV_TAKEOFF to rel_alt_m above home (GUIDED, armed); wait: until within 0.5 m of it.")
      .def(
          "land",
          [](PyVehicle& pv, bool wait, double timeout_s) {
            checked_duration(timeout_s, "timeout_s");
            blocking_result(pv.errors(), [&, &v = pv.v()] { return v.land(wait, timeout_s); });
          },
          py::arg("wait") = false, py::arg("timeout_s") = 120.0)
      .def("return_to_launch",
           [](PyVehicle& pv) {
             blocking_result(pv.errors(), [&, &v = pv.v()] { return v.return_to_launch(); });
           })
      .def(
          "command_long_async",
          [](PyVehicle& pv, std::uint16_t command, const std::array<float, 7>& params,
             std::optional<py::function> done) {
            pv.v().command_long_async(command, params, python_done(pv, done));
          },
          py::arg("command"), py::arg("params"), py::arg("done") = py::none())
      .def(
          "set_mode_async",
          [](PyVehicle& pv, FlightMode mode, std::optional<py::function> done) {
            pv.v().set_mode_async(mode, python_done(pv, done));
          },
          py::arg("mode"), py::arg("done") = py::none(),
          "Sends the command now; done(None or UavsimError) runs on the loop thread later.")
      .def(
          "arm_async",
          [](PyVehicle& pv, std::optional<py::function> done) {
            pv.v().arm_async(python_done(pv, done));
          },
          py::arg("done") = py::none())
      .def(
          "takeoff_async",
          [](PyVehicle& pv, double rel_alt_m, std::optional<py::function> done) {
            pv.v().takeoff_async(rel_alt_m, python_done(pv, done));
          },
          py::arg("rel_alt_m"), py::arg("done") = py::none())
      .def(
          "land_async",
          [](PyVehicle& pv, std::optional<py::function> done) {
            pv.v().land_async(python_done(pv, done));
          },
          py::arg("done") = py::none())
      .def(
          "goto_local_enu",
          [](PyVehicle& pv, const Eigen::Vector3d& enu_m, std::optional<double> yaw) {
            unwrap(pv.v().goto_local_enu(enu_m, optional_angle(yaw, "yaw_enu_rad")));
          },
          py::arg("enu_m"), py::arg("yaw_enu_rad") = py::none(),
          "GUIDED position setpoint in the local ENU frame (m); yaw counter-clockwise from east, "
          "None: keep.")
      .def(
          "goto_local_ned",
          [](PyVehicle& pv, const Eigen::Vector3d& ned_m, std::optional<double> yaw) {
            unwrap(pv.v().goto_local_ned(ned_m, optional_angle(yaw, "yaw_ned_rad")));
          },
          py::arg("ned_m"), py::arg("yaw_ned_rad") = py::none())
      .def(
          "goto_geodetic",
          [](PyVehicle& pv, const client::Geodetic& point_amsl, std::optional<double> yaw) {
            unwrap(pv.v().goto_geodetic(point_amsl, optional_angle(yaw, "yaw_ned_rad")));
          },
          py::arg("point_amsl"), py::arg("yaw_ned_rad") = py::none())
      .def(
          "wait_position_enu",
          [](PyVehicle& pv, const Eigen::Vector3d& enu_m, double tolerance_m, double timeout_s) {
            checked_duration(timeout_s, "timeout_s");
            positive(tolerance_m, "tolerance_m");
            blocking_result(pv.errors(), [&, &v = pv.v()] {
              return v.wait_position_enu(enu_m, tolerance_m, timeout_s);
            });
          },
          py::arg("enu_m"), py::arg("tolerance_m"), py::arg("timeout_s"))
      .def(
          "set_velocity_enu",
          [](PyVehicle& pv, const Eigen::Vector3d& v_m_s, std::optional<double> yaw_rate) {
            unwrap(pv.v().set_velocity_enu(v_m_s, optional_angle(yaw_rate, "yaw_rate_enu_rad_s")));
          },
          py::arg("v_m_s"), py::arg("yaw_rate_enu_rad_s") = py::none(),
          "Velocity (ENU, m/s), re-sent until replaced or stop(); optional yaw rate (rad/s, ENU).")
      .def(
          "set_velocity_enu_yaw",
          [](PyVehicle& pv, const Eigen::Vector3d& v_m_s, double yaw_enu_rad) {
            unwrap(pv.v().set_velocity_enu_yaw(v_m_s, yaw_enu_rad));
          },
          py::arg("v_m_s"), py::arg("yaw_enu_rad"))
      .def(
          "stop", [](PyVehicle& pv) { unwrap(pv.v().stop()); },
          "Ends a velocity command: hold position.")
      .def(
          "set_yaw",
          [](PyVehicle& pv, double heading_deg, double rate_deg_s, bool relative) {
            blocking_result(pv.errors(), [&, &v = pv.v()] {
              return v.set_yaw(heading_deg, rate_deg_s, relative);
            });
          },
          py::arg("heading_deg"), py::arg("rate_deg_s") = 30.0, py::arg("relative") = false)
      .def(
          "point_gimbal",
          [](PyVehicle& pv, double pitch_deg, double yaw_deg, double roll_deg) {
            blocking_result(pv.errors(), [&, &v = pv.v()] {
              return v.point_gimbal(pitch_deg, yaw_deg, roll_deg);
            });
          },
          py::arg("pitch_deg"), py::arg("yaw_deg"), py::arg("roll_deg") = 0.0)
      .def(
          "upload_mission",
          [](PyVehicle& pv, const std::vector<MissionItem>& items, double timeout_s) {
            checked_duration(timeout_s, "timeout_s");
            blocking_result(pv.errors(),
                            [&, &v = pv.v()] { return v.upload_mission(items, timeout_s); });
          },
          py::arg("items"), py::arg("timeout_s") = 10.0)
      .def("start_mission",
           [](PyVehicle& pv) {
             blocking_result(pv.errors(), [&, &v = pv.v()] { return v.start_mission(); });
           })
      .def(
          "get_param",
          [](PyVehicle& pv, const std::string& name, double timeout_s) {
            checked_duration(timeout_s, "timeout_s");
            return blocking_result(pv.errors(),
                                   [&, &v = pv.v()] { return v.get_param(name, timeout_s); });
          },
          py::arg("name"), py::arg("timeout_s") = 3.0)
      .def(
          "set_param",
          [](PyVehicle& pv, const std::string& name, float value, double timeout_s) {
            checked_duration(timeout_s, "timeout_s");
            return blocking_result(
                pv.errors(), [&, &v = pv.v()] { return v.set_param(name, value, timeout_s); });
          },
          py::arg("name"), py::arg("value"), py::arg("timeout_s") = 3.0)
      .def(
          "command_long",
          [](PyVehicle& pv, std::uint16_t command, const std::array<float, 7>& params) {
            blocking_result(pv.errors(),
                            [&, &v = pv.v()] { return v.command_long(command, params); });
          },
          py::arg("command"), py::arg("params"));

  m.def(
      "mode_name", [](FlightMode mode) { return std::string(client::mode_name(mode)); },
      py::arg("mode"));
}

}  // namespace uavsim::python
