// Wind: a mean wind, Dryden-type turbulence and discrete gusts, uniform in space and stepped in sim
// time. A pure library (Eigen and a seeded generator; no clocks, no MuJoCo). The simulation steps
// one WindField per world and subtracts its velocity from each airframe's velocity before the
// quadratic drag (air-relative velocity); balloons sway in it.
//
// Turbulence: each component is a first-order Gauss-Markov process, the time-domain form of the
// Dryden longitudinal spectrum Phi(w) = sigma^2 (2 L / pi V) / (1 + (L w / V)^2) seen by a body
// the mean wind V carries the frozen field past (Taylor's hypothesis; MIL-F-8785C): correlation
// time tau = L / V, stationary standard deviation sigma (the vertical one half of it, as near the
// ground). Discretised exactly, u[k+1] = a u[k] + sigma sqrt(1 - a^2) n[k] with a = exp(-dt / tau),
// so the statistics do not depend on the step. Gusts: discrete "1 - cos" gusts (MIL-F-8785C) along
// the mean wind, at Poisson times (rate gust_rate_hz) or on demand.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <random>
#include <string>

namespace uavsim::server::airframe {

struct WindParams {
  double speed_m_s = 0.0;  // mean wind speed
  double from_deg = 0.0;   // where the mean wind blows from: clockwise from north (meteorology)
  double turbulence_sd_m_s = 0.0;  // sigma of the horizontal turbulence components
  double length_scale_m = 30.0;    // Dryden L (near the ground: tens of metres)
  double gust_rate_hz = 0.0;       // mean rate of random discrete gusts
  double gust_m_s = 0.0;           // peak of a random gust
  double gust_duration_s = 3.0;    // length of a 1 - cos gust
  bool active() const { return speed_m_s != 0.0 || turbulence_sd_m_s > 0.0 || gust_rate_hz > 0.0; }
};
// An empty string if the params are usable, else what is wrong (a negative speed, ...).
std::string validate(const WindParams& params);

class WindField {
 public:
  WindField(const WindParams& params, uint64_t seed);

  // Advances the turbulence and gusts by dt (any dt > 0; the simulation uses its physics step).
  void step(double dt_s);
  // The wind velocity (where the air moves to), ENU.
  const Eigen::Vector3d& velocity_enu_m_s() const { return velocity_enu_m_s_; }
  // The turbulence part alone (velocity minus mean and gust), ENU.
  const Eigen::Vector3d& turbulence_enu_m_s() const { return turbulence_enu_m_s_; }
  // Starts a 1 - cos gust of peak peak_m_s along the mean wind (or from the north if there is none)
  // lasting duration_s; it replaces a gust still running.
  void gust(double peak_m_s, double duration_s);
  // New parameters from now on; the turbulence state is kept (rescaled to the new sigma).
  void set_params(const WindParams& params);
  const WindParams& params() const { return params_; }
  bool active() const { return params_.active() || gust_left_s_ > 0.0; }
  double gust_m_s() const { return gust_now_m_s_; }

 private:
  void update_velocity();

  WindParams params_;
  std::mt19937_64 rng_;
  std::normal_distribution<double> normal_{0.0, 1.0};
  std::uniform_real_distribution<double> uniform_{0.0, 1.0};
  Eigen::Vector3d turbulence_enu_m_s_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d velocity_enu_m_s_ = Eigen::Vector3d::Zero();
  double gust_peak_m_s_ = 0.0;
  double gust_duration_s_ = 0.0;
  double gust_left_s_ = 0.0;
  double gust_now_m_s_ = 0.0;
};

// The unit vector the mean wind blows towards (ENU) for a meteorological "from" direction.
Eigen::Vector3d wind_direction_enu(double from_deg);

}  // namespace uavsim::server::airframe
