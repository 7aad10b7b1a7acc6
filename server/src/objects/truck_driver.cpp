#include "objects/truck_driver.hpp"
#include "uavsim/common/angles.hpp"

#include <cmath>
#include <functional>
#include <random>

namespace uavsim::server::objects {

namespace {
using common::kPi;
// periods of the driver's corrections: steering every 10-40 s, throttle every 15-60 s
constexpr double kLateralPeriodMin_s = 10.0, kLateralPeriodMax_s = 40.0;
constexpr double kWobblePeriodMin_s = 15.0, kWobblePeriodMax_s = 60.0;
constexpr double kMaxLateral_m = 2.0;
constexpr double kMaxWobble = 0.5;
}  // namespace

std::string validate(const DriverParams& p) {
  if (!(p.lateral_amplitude_m >= 0.0 && p.lateral_amplitude_m <= kMaxLateral_m)) {
    return "lateral amplitude must be in [0, 2] m";
  }
  if (!(p.speed_wobble >= 0.0 && p.speed_wobble < kMaxWobble)) {
    return "speed wobble must be in [0, 0.5)";
  }
  return "";
}

TruckDriver::TruckDriver(const DriverParams& params, uint64_t seed, const std::string& salt)
    : params_(params) {
  std::mt19937_64 rng(seed ^ (0x9e3779b97f4a7c15ull * (std::hash<std::string>{}(salt) | 1u)));
  auto draw = [&rng](double bound, double period_min_s, double period_max_s) {
    std::uniform_real_distribution<double> period(period_min_s, period_max_s);
    std::uniform_real_distribution<double> phase(0.0, 2.0 * kPi);
    std::uniform_real_distribution<double> weight(0.5, 1.0);
    Waves w{};
    double total = 0.0;
    for (Wave& x : w) {
      x.omega_rad_s = 2.0 * kPi / period(rng);
      x.phase_rad = phase(rng);
      x.amplitude = weight(rng);
      total += x.amplitude;
    }
    // weights summing to one: the sum never leaves [-bound, bound]
    for (Wave& x : w) x.amplitude *= bound / total;
    return w;
  };
  lateral_ = draw(params.lateral_amplitude_m, kLateralPeriodMin_s, kLateralPeriodMax_s);
  wobble_ = draw(params.speed_wobble, kWobblePeriodMin_s, kWobblePeriodMax_s);
}

double TruckDriver::sum(const Waves& w, double time_s) {
  double out = 0.0;
  for (const Wave& x : w) out += x.amplitude * std::sin(x.omega_rad_s * time_s + x.phase_rad);
  return out;
}

double TruckDriver::integral(const Waves& w, double time_s) {
  // int_0^t a sin(w t + p) = a / w (cos p - cos(w t + p))
  double out = 0.0;
  for (const Wave& x : w) {
    out += x.amplitude / x.omega_rad_s *
           (std::cos(x.phase_rad) - std::cos(x.omega_rad_s * time_s + x.phase_rad));
  }
  return out;
}

double TruckDriver::arc_length_m(const SpeedProfile& schedule, double time_s) const {
  // s(t) = s0 + int_0^t v_schedule (1 + wobble): the schedule is piecewise constant, so per piece
  // v (dt + the wobble's integral over it)
  const double tsw = schedule.switch_time_s;
  if (time_s <= tsw) {
    return schedule.start_s_m + schedule.speed1_m_s * (time_s + integral(wobble_, time_s));
  }
  const double e_sw = integral(wobble_, tsw);
  return schedule.start_s_m + schedule.speed1_m_s * (tsw + e_sw) +
         schedule.speed2_m_s * (time_s - tsw + integral(wobble_, time_s) - e_sw);
}

double TruckDriver::speed_m_s(const SpeedProfile& schedule, double time_s) const {
  return schedule.speed_m_s(time_s) * (1.0 + sum(wobble_, time_s));
}

double TruckDriver::lateral_m(double time_s) const { return sum(lateral_, time_s); }

double TruckDriver::lateral_rate_m_s(double time_s) const {
  double out = 0.0;
  for (const Wave& x : lateral_) {
    out += x.amplitude * x.omega_rad_s * std::cos(x.omega_rad_s * time_s + x.phase_rad);
  }
  return out;
}

}  // namespace uavsim::server::objects
