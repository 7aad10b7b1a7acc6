#include "app/field_setup.hpp"

#include <cmath>

#include "physics/object_bodies.hpp"
#include "uavsim/common/angles.hpp"

namespace uavsim::server::app {

namespace {

using common::kDegToRad;

// a world numeric with at most max_size finite values (empty if absent)
std::vector<double> numeric(const physics::World& world, const std::string& name, size_t min_size,
                            size_t max_size) {
  std::vector<double> v = physics::custom_numeric(world, name);
  if (v.empty()) return v;
  if (v.size() < min_size || v.size() > max_size) {
    throw physics::WorldError("custom numeric '" + name + "' needs " + std::to_string(min_size) +
                              " to " + std::to_string(max_size) + " values, has " +
                              std::to_string(v.size()));
  }
  for (double x : v) {
    if (!std::isfinite(x))
      throw physics::WorldError("custom numeric '" + name + "' has a non-finite value");
  }
  return v;
}

}  // namespace

sim::FieldConditions resolve_field_conditions(const Options& options, const physics::World& world) {
  // the realism level and its defaults
  std::string level = "ideal";
  for (const auto& [name, data] : physics::custom_texts(world, "uavsim:realism")) {
    if (name != "uavsim:realism") continue;
    level = data;
  }
  if (options.realism) level = *options.realism;
  const auto realism = sim::realism_from_name(level);
  if (!realism)
    throw physics::WorldError("custom text 'uavsim:realism': '" + level +
                              "' is not field or ideal");
  sim::FieldConditions c = sim::field_conditions(*realism);

  // the world's own settings
  if (auto w = numeric(world, "uavsim:wind", 2, 6); !w.empty()) {
    c.wind.speed_m_s = w[0];
    c.wind.from_deg = w[1];
    c.wind_from_seeded = false;
    if (w.size() > 2) c.wind.turbulence_sd_m_s = w[2];
    if (w.size() > 3) c.wind.length_scale_m = w[3];
    if (w.size() > 4) c.wind.gust_rate_hz = w[4];
    if (w.size() > 5) c.wind.gust_m_s = w[5];
    if (const std::string e = airframe::validate(c.wind); !e.empty()) {
      throw physics::WorldError("custom numeric 'uavsim:wind': " + e);
    }
  }
  if (auto g = numeric(world, "uavsim:gimbal_dynamics", 1, 3); !g.empty()) {
    c.gimbal.time_const_s = g[0];
    c.gimbal.rate_max_rad_s = g.size() > 1 ? g[1] * kDegToRad : 0.0;
    c.gimbal.accel_max_rad_s2 = g.size() > 2 ? g[2] * kDegToRad : 0.0;
    if (c.gimbal.time_const_s < 0 || c.gimbal.time_const_s > 10 || c.gimbal.rate_max_rad_s < 0 ||
        c.gimbal.accel_max_rad_s2 < 0) {
      throw physics::WorldError(
          "custom numeric 'uavsim:gimbal_dynamics': time constant in [0, 10] s, limits >= 0");
    }
  }
  if (auto b = numeric(world, "uavsim:balloon_variation", 1, 2); !b.empty()) {
    c.balloons.height_spread_m = b[0];
    c.balloons.sway = b.size() > 1 && b[1] != 0.0;
    if (b[0] < 0 || b[0] > 0.6) {
      throw physics::WorldError(
          "custom numeric 'uavsim:balloon_variation': height spread in [0, 0.6] m "
          "(the pole reaches 0.6 m under its foot)");
    }
  }
  if (auto r = numeric(world, "uavsim:battery_sag", 1, 1); !r.empty()) {
    if (r[0] < 0 || r[0] > 1)
      throw physics::WorldError("custom numeric 'uavsim:battery_sag': resistance in [0, 1] ohm");
    c.battery_resistance_ohm = r[0];
  }

  // the command line's wind over both
  if (options.wind) {
    c.wind.speed_m_s = options.wind->speed_m_s;
    c.wind.from_deg = options.wind->from_deg;
    c.wind_from_seeded = false;
    if (options.wind->turbulence_sd_m_s)
      c.wind.turbulence_sd_m_s = *options.wind->turbulence_sd_m_s;
  }
  return c;
}

}  // namespace uavsim::server::app
