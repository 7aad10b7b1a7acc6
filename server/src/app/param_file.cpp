#include "app/param_file.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <map>
#include <optional>
#include <sstream>
#include <stdexcept>

#include "fc/params.hpp"

namespace uavsim::server::app {

namespace {

// units and meaning of each parameter, for the documentation (ArduCopter's where it has the parameter)
struct ParamDoc {
  const char* units;
  const char* meaning;
};

const std::map<std::string, ParamDoc>& param_docs() {
  static const std::map<std::string, ParamDoc> docs = {
      {"SYSID_THISMAV", {"", "MAVLink system id (the server gives vehicle i the id i + 1)"}},
      {"PSC_POSXY_P", {"1/s", "horizontal position P: velocity per metre of error"}},
      {"PSC_VELXY_P", {"1/s", "horizontal velocity P: acceleration per m/s of error"}},
      {"PSC_VELXY_I", {"1/s^2", "horizontal velocity I"}},
      {"PSC_VELXY_D", {"", "horizontal velocity D"}},
      {"PSC_VELXY_IMAX", {"cm/s/s", "horizontal velocity integrator limit"}},
      {"PSC_POSZ_P", {"1/s", "vertical position P"}},
      {"PSC_VELZ_P", {"1/s", "vertical velocity P"}},
      {"PSC_ACCZ_P", {"", "vertical acceleration P"}},
      {"PSC_ACCZ_I", {"", "vertical acceleration I"}},
      {"PSC_ACCZ_IMAX", {"cm/s/s", "vertical acceleration integrator limit (ArduCopter: throttle permille)"}},
      {"ATC_ANG_RLL_P", {"1/s", "roll angle P: rate per radian of error"}},
      {"ATC_ANG_PIT_P", {"1/s", "pitch angle P"}},
      {"ATC_ANG_YAW_P", {"1/s", "yaw angle P"}},
      {"ATC_RAT_RLL_P", {"1/s", "roll rate P (angular acceleration per rad/s, times the inertia)"}},
      {"ATC_RAT_RLL_I", {"1/s^2", "roll rate I"}},
      {"ATC_RAT_RLL_D", {"", "roll rate D"}},
      {"ATC_RAT_RLL_IMAX", {"rad/s/s", "roll rate integrator limit"}},
      {"ATC_RAT_RLL_FLTD", {"Hz", "roll rate D-term low-pass cut-off"}},
      {"ATC_RAT_PIT_P", {"1/s", "pitch rate P"}},
      {"ATC_RAT_PIT_I", {"1/s^2", "pitch rate I"}},
      {"ATC_RAT_PIT_D", {"", "pitch rate D"}},
      {"ATC_RAT_PIT_IMAX", {"rad/s/s", "pitch rate integrator limit"}},
      {"ATC_RAT_PIT_FLTD", {"Hz", "pitch rate D-term low-pass cut-off"}},
      {"ATC_RAT_YAW_P", {"1/s", "yaw rate P"}},
      {"ATC_RAT_YAW_I", {"1/s^2", "yaw rate I"}},
      {"ATC_RAT_YAW_IMAX", {"rad/s/s", "yaw rate integrator limit"}},
      {"ATC_RATE_RP_MAX", {"deg/s", "roll and pitch rate limit (ArduCopter ATC_RATE_R_MAX / ATC_RATE_P_MAX)"}},
      {"ATC_RATE_Y_MAX", {"deg/s", "yaw rate limit"}},
      {"ATC_SLEW_YAW", {"cdeg/s", "slew rate of the yaw target in autonomous modes"}},
      {"ANGLE_MAX", {"cdeg", "lean angle limit"}},
      {"WPNAV_SPEED", {"cm/s", "horizontal speed in AUTO, GUIDED position targets and RTL"}},
      {"WPNAV_SPEED_UP", {"cm/s", "climb speed of waypoint navigation"}},
      {"WPNAV_SPEED_DN", {"cm/s", "descent speed of waypoint navigation"}},
      {"WPNAV_ACCEL", {"cm/s/s", "horizontal acceleration of waypoint navigation"}},
      {"WPNAV_ACCEL_Z", {"cm/s/s", "vertical acceleration of waypoint navigation"}},
      {"WPNAV_RADIUS", {"cm", "distance at which a waypoint counts as reached"}},
      {"WP_YAW_BEHAVIOR", {"", "yaw in AUTO: 0 keep, 1 face the next waypoint, 2 ditto except in RTL, 3 along the path"}},
      {"LAND_SPEED", {"cm/s", "final descent speed of LAND and RTL"}},
      {"LAND_SPEED_HIGH", {"cm/s", "descent speed above 10 m; 0: WPNAV_SPEED_DN"}},
      {"RTL_ALT", {"cm", "altitude above home RTL climbs to before returning"}},
      {"RTL_SPEED", {"cm/s", "horizontal speed of RTL; 0: WPNAV_SPEED"}},
      {"RTL_LOIT_TIME", {"ms", "time RTL hovers over home before landing"}},
      {"PILOT_TKOFF_ALT", {"cm", "take-off altitude when a take-off command gives none"}},
      {"PILOT_SPEED_UP", {"cm/s", "climb rate of a take-off and full throttle in ALT_HOLD/LOITER"}},
      {"PILOT_SPEED_DN", {"cm/s", "descent rate at zero throttle in ALT_HOLD/LOITER; 0: PILOT_SPEED_UP"}},
      {"FS_GCS_ENABLE", {"", "ground-station failsafe: 0 off, 1 RTL when GCS heartbeats stop"}},
      {"FS_GCS_TIMEOUT", {"s", "heartbeat silence that triggers the ground-station failsafe"}},
      {"FS_BATT_ENABLE", {"", "battery failsafe: 0 off, 1 LAND, 2 RTL"}},
      {"BATT_CAPACITY", {"mAh", "battery capacity (default: the airframe's)"}},
      {"BATT_LOW_MAH", {"mAh", "remaining capacity that triggers the battery failsafe (default 20 %)"}},
      {"FS_EKF_ACTION", {"", "0 off, 1 LAND when GPS is lost in a position mode"}},
      {"ARMING_CHECK", {"", "0 skip the pre-arm checks, 1 run them all"}},
      {"DISARM_DELAY", {"s", "time on the ground after landing before auto-disarm; 0 never"}},
      {"MOT_SPIN_ARM", {"", "motor command while armed on the ground (0 to 1)"}},
      {"GUID_TIMEOUT", {"s", "GUIDED velocity, acceleration and attitude targets expire after this"}},
      {"SIM_GPS_HZ", {"Hz", "simulated GPS fix rate"}},
      {"SIM_GPS_POS_H_SD", {"m", "simulated GPS horizontal position noise (standard deviation)"}},
      {"SIM_GPS_POS_V_SD", {"m", "simulated GPS vertical position noise"}},
      {"SIM_GPS_VEL_SD", {"m/s", "simulated GPS velocity noise"}},
      {"SIM_GPS_NUMSATS", {"", "satellites the simulated GPS reports"}},
      {"SIM_GPS_HDOP", {"", "HDOP the simulated GPS reports"}},
      {"SIM_BARO_HZ", {"Hz", "simulated barometer rate"}},
      {"SIM_BARO_SD", {"m", "simulated barometer altitude noise"}},
      {"SIM_MAG_HZ", {"Hz", "simulated compass rate"}},
      {"SIM_MAG_SD", {"rad", "simulated compass heading noise"}},
      {"SIM_GYRO_SD", {"rad/s", "simulated gyro noise"}},
      {"SIM_ACCEL_SD", {"m/s/s", "simulated accelerometer noise"}},
      {"RC_OVERRIDE_TIME", {"s", "how long RC_CHANNELS_OVERRIDE / MANUAL_CONTROL sticks last; 0 ignores them, -1 never expires"}},
      {"SIM_GPS_BIAS_SD", {"m", "simulated GPS wandering horizontal bias (Gauss-Markov, stationary sd; vertical twice)"}},
      {"SIM_GPS_BIAS_TAU", {"s", "correlation time of the simulated GPS bias"}},
      {"SIM_GPS_JUMP_HZ", {"Hz", "mean rate of simulated GPS position jumps"}},
      {"SIM_GPS_JUMP_M", {"m", "size (sd) of a simulated GPS jump; it decays with the bias"}},
      {"SIM_GPS_RTK", {"", "1: simulated RTK fixed GPS (1 cm horizontal, 2 cm vertical noise, no bias)"}},
      {"SIM_BARO_DRIFT", {"m", "simulated barometer drift (Gauss-Markov over 300 s, stationary sd)"}},
      {"SIM_MAG_OFS_SD", {"rad", "sd of the simulated compass heading offset drawn once per vehicle"}},
  };
  return docs;
}

std::string number_text(double v) {
  std::ostringstream os;
  os << v;
  return os.str();
}

std::string trim(const std::string& s) {
  const auto first = s.find_first_not_of(" \t\r\n");
  if (first == std::string::npos) return "";
  return s.substr(first, s.find_last_not_of(" \t\r\n") - first + 1);
}

}  // namespace

std::vector<ParamAssignment> parse_param_text(const std::string& text, const std::string& source) {
  const std::vector<fc::ParamInfo> table = fc::param_info(5000.0);
  std::vector<ParamAssignment> out;
  // entries: lines, and ';'-separated parts of a line (the world's one-line texts)
  std::size_t line_no = 0;
  std::istringstream lines(text);
  std::string line;
  while (std::getline(lines, line)) {
    ++line_no;
    std::istringstream parts(line.substr(0, line.find('#')));
    std::string entry;
    while (std::getline(parts, entry, ';')) {
      entry = trim(entry);
      if (entry.empty()) continue;
      const std::string where = source + ":" + std::to_string(line_no);
      // NAME VALUE, NAME,VALUE or NAME<TAB>VALUE
      const auto sep = entry.find_first_of(" \t,");
      const std::string name = entry.substr(0, sep);
      const std::string value_text = sep == std::string::npos ? "" : trim(entry.substr(sep + 1));
      char* end = nullptr;
      const double value = std::strtod(value_text.c_str(), &end);
      if (value_text.empty() || *end != '\0' || !std::isfinite(value)) {
        throw std::invalid_argument(where + ": '" + entry + "' is not NAME VALUE (or NAME,VALUE)");
      }
      auto info = std::find_if(table.begin(), table.end(), [&](const fc::ParamInfo& p) { return p.name == name; });
      if (info == table.end()) {
        throw std::invalid_argument(where + ": unknown parameter " + name + " (docs/parameters.md lists them)");
      }
      if (value < info->min || value > info->max) {
        throw std::invalid_argument(where + ": " + name + " " + value_text + " is out of its range " +
                                    number_text(info->min) + " to " + number_text(info->max));
      }
      out.push_back({name, value, where});
    }
  }
  return out;
}

std::vector<ParamAssignment> read_param_file(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::invalid_argument("--defaults: cannot read '" + path + "'");
  std::stringstream text;
  text << in.rdbuf();
  return parse_param_text(text.str(), path);
}

std::vector<std::vector<std::pair<std::string, double>>> vehicle_params(
    const std::vector<std::string>& vehicle_names, const std::vector<std::pair<std::string, std::string>>& world_texts,
    const std::vector<std::string>& files) {
  static const std::string kPrefix = "uavsim:params:";
  std::vector<std::vector<std::pair<std::string, double>>> per_vehicle(vehicle_names.size());
  auto apply = [&](const std::vector<ParamAssignment>& list, std::optional<std::size_t> only) {
    for (std::size_t i = 0; i < per_vehicle.size(); ++i) {
      if (only && *only != i) continue;
      for (const ParamAssignment& a : list) per_vehicle[i].emplace_back(a.name, a.value);
    }
  };
  // the world: every vehicle's first, then each vehicle's own
  for (const bool everyone : {true, false}) {
    for (const auto& [text_name, data] : world_texts) {
      if (text_name.rfind(kPrefix, 0) != 0) continue;
      const std::string target = text_name.substr(kPrefix.size());
      if ((target == "*") != everyone) continue;
      const auto list = parse_param_text(data, "world text " + text_name);
      if (everyone) {
        apply(list, std::nullopt);
        continue;
      }
      const auto it = std::find(vehicle_names.begin(), vehicle_names.end(), target);
      if (it == vehicle_names.end()) {
        throw std::invalid_argument("world text " + text_name + ": the world has no vehicle '" + target + "'");
      }
      apply(list, static_cast<std::size_t>(it - vehicle_names.begin()));
    }
  }
  for (const std::string& f : files) apply(read_param_file(f), std::nullopt);
  return per_vehicle;
}

std::string params_markdown() {
  std::ostringstream md;
  md << "# Flight-controller parameters\n\n"
        "Generated by `uavsim-server --list-params` from the flight controller's table (a test checks that this\n"
        "file is up to date). Names, units and meanings follow ArduCopter where it has the parameter; `SIM_*`\n"
        "are the simulated sensors'. Ground stations read and set them over MAVLink (PARAM_REQUEST_LIST,\n"
        "PARAM_SET); `--defaults FILE.parm` and the world's `uavsim:params:*` texts set them at start. Values\n"
        "outside the range are refused. Defaults are a 5000 mAh vehicle's (BATT_CAPACITY and BATT_LOW_MAH follow\n"
        "the airframe's battery).\n\n"
        "| name | default | min | max | units | meaning |\n"
        "|---|---|---|---|---|---|\n";
  for (const fc::ParamInfo& p : fc::param_info(5000.0)) {
    const auto doc = param_docs().find(p.name);
    const ParamDoc d = doc == param_docs().end() ? ParamDoc{"", ""} : doc->second;
    md << "| `" << p.name << "` | " << number_text(p.default_value) << " | " << number_text(p.min) << " | "
       << number_text(p.max) << " | " << d.units << " | " << d.meaning << " |\n";
  }
  return md.str();
}

}  // namespace uavsim::server::app
