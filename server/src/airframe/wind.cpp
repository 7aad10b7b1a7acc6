#include "airframe/wind.hpp"
#include "uavsim/common/angles.hpp"

#include <algorithm>
#include <cmath>
#include <string>

namespace uavsim::server::airframe {

namespace {
using common::kDegToRad;
constexpr double kMinAdvection_m_s = 1.0;  // below this the frozen field passes at walking pace
constexpr double kVerticalSdRatio =
    0.5;  // sigma_w / sigma_u near the ground (MIL-F-8785C low altitude)
}  // namespace

std::string validate(const WindParams& p) {
  const double v[] = {p.speed_m_s,    p.from_deg, p.turbulence_sd_m_s, p.length_scale_m,
                      p.gust_rate_hz, p.gust_m_s, p.gust_duration_s};
  for (double x : v) {
    if (!std::isfinite(x)) return "wind values must be finite";
  }
  if (p.speed_m_s < 0 || p.speed_m_s > 50) return "wind speed must be in [0, 50] m/s";
  if (p.turbulence_sd_m_s < 0 || p.turbulence_sd_m_s > 20)
    return "turbulence sd must be in [0, 20] m/s";
  if (!(p.length_scale_m > 0)) return "turbulence length scale must be > 0";
  if (p.gust_rate_hz < 0 || p.gust_m_s < 0 || p.gust_m_s > 50)
    return "gust rate and peak must be >= 0";
  if (!(p.gust_duration_s > 0)) return "gust duration must be > 0";
  return "";
}

Eigen::Vector3d wind_direction_enu(double from_deg) {
  // from the north (0 deg) means blowing towards the south: -north = -y in ENU
  const double a = from_deg * kDegToRad;
  return Eigen::Vector3d(-std::sin(a), -std::cos(a), 0.0);
}

WindField::WindField(const WindParams& params, uint64_t seed) : params_(params), rng_(seed) {
  // start from the stationary distribution so statistics hold from t = 0
  const double sd = params_.turbulence_sd_m_s;
  if (sd > 0) {
    turbulence_enu_m_s_ = Eigen::Vector3d(sd * normal_(rng_), sd * normal_(rng_),
                                          kVerticalSdRatio * sd * normal_(rng_));
  }
  update_velocity();
}

void WindField::set_params(const WindParams& params) {
  const double old_sd = params_.turbulence_sd_m_s;
  params_ = params;
  if (old_sd > 0) {
    turbulence_enu_m_s_ *= params_.turbulence_sd_m_s / old_sd;
  } else {
    turbulence_enu_m_s_.setZero();
  }
  update_velocity();
}

void WindField::gust(double peak_m_s, double duration_s) {
  gust_peak_m_s_ = peak_m_s;
  gust_duration_s_ = std::max(duration_s, 1e-3);
  gust_left_s_ = gust_duration_s_;
  update_velocity();
}

void WindField::step(double dt_s) {
  // turbulence: exact first-order Gauss-Markov step, correlation time L / V
  const double sd = params_.turbulence_sd_m_s;
  if (sd > 0) {
    const double tau_s = params_.length_scale_m / std::max(params_.speed_m_s, kMinAdvection_m_s);
    const double a = std::exp(-dt_s / tau_s);
    const double b = std::sqrt(1.0 - a * a);
    turbulence_enu_m_s_.x() = a * turbulence_enu_m_s_.x() + b * sd * normal_(rng_);
    turbulence_enu_m_s_.y() = a * turbulence_enu_m_s_.y() + b * sd * normal_(rng_);
    turbulence_enu_m_s_.z() =
        a * turbulence_enu_m_s_.z() + b * kVerticalSdRatio * sd * normal_(rng_);
  }
  // gusts: the running one advances; a new one starts with probability rate * dt
  if (gust_left_s_ > 0) gust_left_s_ = std::max(0.0, gust_left_s_ - dt_s);
  if (params_.gust_rate_hz > 0 && uniform_(rng_) < params_.gust_rate_hz * dt_s &&
      gust_left_s_ <= 0) {
    gust(params_.gust_m_s, params_.gust_duration_s);
  }
  update_velocity();
}

void WindField::update_velocity() {
  // 1 - cos gust profile: 0 at both ends, the peak halfway
  gust_now_m_s_ = 0.0;
  if (gust_left_s_ > 0) {
    const double phase = 1.0 - gust_left_s_ / gust_duration_s_;
    gust_now_m_s_ = 0.5 * gust_peak_m_s_ * (1.0 - std::cos(2.0 * common::kPi * phase));
  }
  const Eigen::Vector3d dir = wind_direction_enu(params_.from_deg);
  velocity_enu_m_s_ = (params_.speed_m_s + gust_now_m_s_) * dir + turbulence_enu_m_s_;
}

}  // namespace uavsim::server::airframe
