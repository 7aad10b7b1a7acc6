#include "fc/mixer.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace uavsim::server::fc {

namespace {
constexpr std::size_t kNoLostRotor = kMaxRotors;
// bisection steps for the degraded mixer's roll/pitch scale: 2^-12 of the demand
constexpr int kScaleBisections = 12;
// the share of each rotor's thrust range yaw keeps even when the collective demand needs it all;
// ArduCopter's MOT_YAW_HEADROOM default is 200 of the 1000 us output range
constexpr double kYawHeadroom = 0.2;
}  // namespace

Mixer::Mixer(const airframe::AirframeParams& airframe) { build(airframe, kNoLostRotor); }

Mixer::Mixer(const airframe::AirframeParams& airframe, std::size_t lost_rotor) {
  if (lost_rotor >= airframe.rotors.size()) {
    throw std::invalid_argument("airframe '" + airframe.frame + "': no rotor " +
                                std::to_string(lost_rotor) + " to leave out");
  }
  build(airframe, lost_rotor);
}

void Mixer::build(const airframe::AirframeParams& airframe, std::size_t lost_rotor) {
  n_ = airframe.rotors.size();
  degraded_ = lost_rotor < n_;
  if (n_ == 0 || n_ > kMaxRotors) {
    throw std::invalid_argument("airframe '" + airframe.frame + "': rotor count " +
                                std::to_string(n_) + " not in [1, 12]");
  }
  // allocation matrix about the centre of mass: r x (0, 0, T) = (y T, -x T, 0), reaction torque
  // -spin_dir * torque_coef * T about z (the plant's convention, airframe.hpp); a lost rotor's
  // column is zero
  a_.resize(4, static_cast<Eigen::Index>(n_));
  max_total_thrust_n_ = 0.0;
  for (std::size_t k = 0; k < n_; ++k) {
    const airframe::RotorParams& r = airframe.rotors[k];
    const Eigen::Vector3d arm = r.position_body_m - airframe.com_body_m;
    const auto c = static_cast<Eigen::Index>(k);
    const double live = k == lost_rotor ? 0.0 : 1.0;
    a_(0, c) = live * arm.y();
    a_(1, c) = live * -arm.x();
    a_(2, c) = live * -r.spin_dir * r.torque_coef_m;
    a_(3, c) = live;
    max_thrust_n_[k] = r.max_thrust_n;
    max_total_thrust_n_ += live * r.max_thrust_n;
    if (!(r.max_thrust_n > 0.0)) {
      throw std::invalid_argument("airframe '" + airframe.frame + "': rotor " + std::to_string(k) +
                                  " max_thrust_n must be > 0");
    }
  }
  // pseudo-inverse B = A^T (A A^T)^-1 (seed eq. 4.5 is the square case)
  const Eigen::Matrix4d aat = a_ * a_.transpose();
  Eigen::FullPivLU<Eigen::Matrix4d> lu(aat);
  Eigen::MatrixXd b;
  if (lu.rank() == 4) {
    b = a_.transpose() * lu.inverse();
  } else if (degraded_) {
    // roll, pitch and thrust only; yaw is not controllable with this rotor gone
    Eigen::Matrix<double, 3, Eigen::Dynamic> a3(3, a_.cols());
    a3 << a_.row(0), a_.row(1), a_.row(3);
    Eigen::FullPivLU<Eigen::Matrix3d> lu3(a3 * a3.transpose());
    if (lu3.rank() < 3) {
      throw std::invalid_argument("airframe '" + airframe.frame + "' without rotor " +
                                  std::to_string(lost_rotor) +
                                  ": cannot control roll, pitch and thrust");
    }
    const Eigen::MatrixXd b3 = a3.transpose() * lu3.inverse();
    b = Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(n_), 4);
    b.col(0) = b3.col(0);
    b.col(1) = b3.col(1);
    b.col(3) = b3.col(2);
  } else {
    throw std::invalid_argument("airframe '" + airframe.frame +
                                "': rotor layout cannot control roll, pitch, yaw and thrust");
  }
  max_live_thrust_n_ = std::numeric_limits<double>::infinity();
  for (std::size_t k = 0; k < n_; ++k) {
    const auto r = static_cast<Eigen::Index>(k);
    b_roll_[k] = b(r, 0);
    b_pitch_[k] = b(r, 1);
    b_yaw_[k] = b(r, 2);
    b_thrust_[k] = b(r, 3);
    if (degraded_) {
      // a live rotor with no share of the collective (the one opposite the lost rotor on a hexa) is
      // a torque-only actuator; round-off must not make its share negative
      if (std::abs(b_thrust_[k]) < 1e-9) b_thrust_[k] = 0.0;
      if (b_thrust_[k] < 0.0) {
        throw std::invalid_argument("airframe '" + airframe.frame + "' without rotor " +
                                    std::to_string(lost_rotor) +
                                    ": collective thrust does not raise every live rotor");
      }
      if (b_thrust_[k] > 0.0)
        max_live_thrust_n_ = std::min(max_live_thrust_n_, max_thrust_n_[k] / b_thrust_[k]);
      continue;
    }
    // the desaturation below shifts collective thrust along B's thrust column: needs all > 0
    if (!(b_thrust_[k] > 0.0)) {
      throw std::invalid_argument("airframe '" + airframe.frame +
                                  "': collective thrust does not raise every rotor");
    }
  }
}

MixerStatus Mixer::mix(const Eigen::Vector3d& torque_body_nm, double thrust_n,
                       double* rotor_thrust_n, double* motor_cmd) const {
  if (degraded_) return mix_degraded(torque_body_nm, thrust_n, rotor_thrust_n, motor_cmd);
  // rotor k: thrust_k = s*rp_k + t*yaw_k + F*u_k with 0 <= thrust_k <= max_k. Divided by u_k:
  // -(s a_k + t b_k) <= F <= M_k - s a_k - t b_k, so a feasible F exists iff for every pair (i, j)
  // s (a_j - a_i) + t (b_j - b_i) <= M_j. Pick the largest s, then the largest t, then clamp F.
  std::array<double, kMaxRotors> a{}, b{}, m{};
  for (std::size_t k = 0; k < n_; ++k) {
    const double rp = b_roll_[k] * torque_body_nm.x() + b_pitch_[k] * torque_body_nm.y();
    a[k] = rp / b_thrust_[k];
    b[k] = b_yaw_[k] * torque_body_nm.z() / b_thrust_[k];
    m[k] = max_thrust_n_[k] / b_thrust_[k];
  }
  MixerStatus status;
  // 1. roll/pitch scale
  double s = 1.0;
  for (std::size_t i = 0; i < n_; ++i) {
    for (std::size_t j = 0; j < n_; ++j) {
      const double d = a[j] - a[i];
      if (d > 0.0) s = std::min(s, m[j] / d);
    }
  }
  // 2. yaw scale. t_fit: the most yaw that fits beside roll/pitch at any collective; t_thrust: the
  // most that fits beside roll/pitch at the demanded collective (clamped into the range roll/pitch
  // leave); t_reserve: yaw whose per-rotor share stays within kYawHeadroom of the rotor's range.
  // Yaw gets t_thrust, or up to t_reserve where that is more: beyond its reserve, yaw never takes
  // the thrust the demand needs (a climb demanded near the ground once sank into it while turning).
  double t_fit = 1.0;
  for (std::size_t i = 0; i < n_; ++i) {
    for (std::size_t j = 0; j < n_; ++j) {
      const double d = b[j] - b[i];
      if (d > 0.0) t_fit = std::min(t_fit, (m[j] - s * (a[j] - a[i])) / d);
    }
  }
  t_fit = std::max(t_fit, 0.0);
  double rp_lo = -std::numeric_limits<double>::infinity();
  double rp_hi = std::numeric_limits<double>::infinity();
  for (std::size_t k = 0; k < n_; ++k) {
    rp_lo = std::max(rp_lo, -s * a[k]);
    rp_hi = std::min(rp_hi, m[k] - s * a[k]);
  }
  const double f_demand = std::clamp(thrust_n, rp_lo, std::max(rp_lo, rp_hi));
  double t_thrust = 1.0, t_reserve = 1.0;
  for (std::size_t k = 0; k < n_; ++k) {
    const double base = f_demand + s * a[k];
    if (b[k] > 0.0) t_thrust = std::min(t_thrust, (m[k] - base) / b[k]);
    if (b[k] < 0.0) t_thrust = std::min(t_thrust, base / -b[k]);
    if (b[k] != 0.0) t_reserve = std::min(t_reserve, kYawHeadroom * m[k] / std::abs(b[k]));
  }
  const double t = std::min(t_fit, std::max(t_thrust, t_reserve));
  // 3. collective thrust into the range left
  double lo = -std::numeric_limits<double>::infinity();
  double hi = std::numeric_limits<double>::infinity();
  for (std::size_t k = 0; k < n_; ++k) {
    const double torque_part = s * a[k] + t * b[k];
    lo = std::max(lo, -torque_part);
    hi = std::min(hi, m[k] - torque_part);
  }
  const double f = std::clamp(thrust_n, lo, std::max(lo, hi));
  status.roll_pitch_scale = s;
  status.yaw_scale = t;
  status.thrust_n = f;
  status.limit_thrust_up = thrust_n > f;
  status.limit_thrust_down = thrust_n < f;
  // per-rotor thrust and the inverse square law
  for (std::size_t k = 0; k < n_; ++k) {
    const double tk = std::clamp(b_thrust_[k] * (f + s * a[k] + t * b[k]), 0.0, max_thrust_n_[k]);
    rotor_thrust_n[k] = tk;
    motor_cmd[k] = std::sqrt(tk / max_thrust_n_[k]);
  }
  return status;
}

MixerStatus Mixer::mix_degraded(const Eigen::Vector3d& torque_body_nm, double thrust_n,
                                double* rotor_thrust_n, double* motor_cmd) const {
  // rotor k: thrust_k = s*rp_k + F*u_k + y*yaw_k with 0 <= thrust_k <= max_k, y the yaw torque
  // actually given. Thrust first goes into what the live rotors carry at zero torque; then the
  // largest roll/pitch scale s for which some y keeps every rotor in range (bisection: the feasible
  // y form an interval that shrinks as s grows); then y is the demand clamped into that interval.
  const double f = std::clamp(thrust_n, 0.0, max_live_thrust_n_);
  std::array<double, kMaxRotors> rp{}, base{};
  for (std::size_t k = 0; k < n_; ++k) {
    rp[k] = b_roll_[k] * torque_body_nm.x() + b_pitch_[k] * torque_body_nm.y();
  }
  // the interval of yaw torque that keeps every rotor in range at roll/pitch scale s
  auto yaw_range = [&](double s, double* lo, double* hi) {
    *lo = -std::numeric_limits<double>::infinity();
    *hi = std::numeric_limits<double>::infinity();
    for (std::size_t k = 0; k < n_; ++k) {
      const double t0 = s * rp[k] + f * b_thrust_[k];
      const double y = b_yaw_[k];
      if (std::abs(y) < 1e-12) {
        if (t0 < -1e-9 || t0 > max_thrust_n_[k] + 1e-9)
          *lo = std::numeric_limits<double>::infinity();
        continue;
      }
      const double a = -t0 / y;
      const double b = (max_thrust_n_[k] - t0) / y;
      *lo = std::max(*lo, std::min(a, b));
      *hi = std::min(*hi, std::max(a, b));
    }
    return *lo <= *hi;
  };
  double s = 1.0, lo = 0.0, hi = 0.0;
  if (!yaw_range(1.0, &lo, &hi)) {
    // s = 0 is feasible: f is within what the live rotors carry at zero torque (y = 0)
    double s_ok = 0.0, s_bad = 1.0;
    for (int i = 0; i < kScaleBisections; ++i) {
      const double mid = 0.5 * (s_ok + s_bad);
      if (yaw_range(mid, &lo, &hi)) {
        s_ok = mid;
      } else {
        s_bad = mid;
      }
    }
    s = s_ok;
    yaw_range(s, &lo, &hi);
  }
  const double yaw = std::clamp(torque_body_nm.z(), lo, std::max(lo, hi));
  MixerStatus status;
  status.roll_pitch_scale = s;
  const double yaw_demand = torque_body_nm.z();
  status.yaw_scale =
      std::abs(yaw - yaw_demand) < 1e-12
          ? 1.0
          : (std::abs(yaw_demand) > 1e-12 ? std::clamp(yaw / yaw_demand, 0.0, 1.0) : 0.0);
  status.thrust_n = f;
  status.limit_thrust_up = thrust_n > f;
  status.limit_thrust_down = thrust_n < f;
  for (std::size_t k = 0; k < n_; ++k) base[k] = s * rp[k] + f * b_thrust_[k] + yaw * b_yaw_[k];
  for (std::size_t k = 0; k < n_; ++k) {
    const double tk = a_(3, static_cast<Eigen::Index>(k)) > 0.0
                          ? std::clamp(base[k], 0.0, max_thrust_n_[k])
                          : 0.0;
    rotor_thrust_n[k] = tk;
    motor_cmd[k] = std::sqrt(tk / max_thrust_n_[k]);
  }
  return status;
}

}  // namespace uavsim::server::fc
