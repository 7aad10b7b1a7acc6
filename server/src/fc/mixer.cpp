#include "fc/mixer.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace uavsim::server::fc {

Mixer::Mixer(const airframe::AirframeParams& airframe) : n_(airframe.rotors.size()) {
  if (n_ == 0 || n_ > kMaxRotors) {
    throw std::invalid_argument("airframe '" + airframe.frame + "': rotor count " +
                                std::to_string(n_) + " not in [1, 12]");
  }
  // allocation matrix about the centre of mass: r x (0, 0, T) = (y T, -x T, 0), reaction torque
  // -spin_dir * torque_coef * T about z (the plant's convention, airframe.hpp)
  a_.resize(4, static_cast<Eigen::Index>(n_));
  for (std::size_t k = 0; k < n_; ++k) {
    const airframe::RotorParams& r = airframe.rotors[k];
    const Eigen::Vector3d arm = r.position_body_m - airframe.com_body_m;
    const auto c = static_cast<Eigen::Index>(k);
    a_(0, c) = arm.y();
    a_(1, c) = -arm.x();
    a_(2, c) = -r.spin_dir * r.torque_coef_m;
    a_(3, c) = 1.0;
    max_thrust_n_[k] = r.max_thrust_n;
    max_total_thrust_n_ += r.max_thrust_n;
    if (!(r.max_thrust_n > 0.0)) {
      throw std::invalid_argument("airframe '" + airframe.frame + "': rotor " + std::to_string(k) +
                                  " max_thrust_n must be > 0");
    }
  }
  // pseudo-inverse B = A^T (A A^T)^-1 (seed eq. 4.5 is the square case)
  const Eigen::Matrix4d aat = a_ * a_.transpose();
  Eigen::FullPivLU<Eigen::Matrix4d> lu(aat);
  if (lu.rank() < 4) {
    throw std::invalid_argument("airframe '" + airframe.frame +
                                "': rotor layout cannot control roll, pitch, yaw and thrust");
  }
  const Eigen::MatrixXd b = a_.transpose() * lu.inverse();
  for (std::size_t k = 0; k < n_; ++k) {
    const auto r = static_cast<Eigen::Index>(k);
    b_roll_[k] = b(r, 0);
    b_pitch_[k] = b(r, 1);
    b_yaw_[k] = b(r, 2);
    b_thrust_[k] = b(r, 3);
    // the desaturation below shifts collective thrust along B's thrust column: needs all > 0
    if (!(b_thrust_[k] > 0.0)) {
      throw std::invalid_argument("airframe '" + airframe.frame +
                                  "': collective thrust does not raise every rotor");
    }
  }
}

MixerStatus Mixer::mix(const Eigen::Vector3d& torque_body_nm, double thrust_n,
                       double* rotor_thrust_n, double* motor_cmd) const {
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
  // 2. yaw scale, beside the roll/pitch already granted
  double t = 1.0;
  for (std::size_t i = 0; i < n_; ++i) {
    for (std::size_t j = 0; j < n_; ++j) {
      const double d = b[j] - b[i];
      if (d > 0.0) t = std::min(t, (m[j] - s * (a[j] - a[i])) / d);
    }
  }
  t = std::max(t, 0.0);
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

}  // namespace uavsim::server::fc
