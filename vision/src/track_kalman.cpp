#include "uavsim/vision/track_kalman.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>

namespace uavsim::vision {

namespace {

constexpr double kMaxInitSpeedM_S = 15.0;  // faster than any truck: the two points were mismatched
constexpr double kInitSigmaVlM_S = 0.3;    // lateral speed starts at 0 with this uncertainty

double us_to_s(int64_t us) { return 1e-6 * static_cast<double>(us); }

}  // namespace

TrackKalman::TrackKalman(const EightTrack& track, const TrackKalmanParams& params)
    : track_(track), params_(params) {}

void TrackKalman::reset() {
  initialised_ = false;
  first_point_.reset();
  history_.clear();
  rejections_in_a_row_ = 0;
  x_.setZero();
  P_.setZero();
  stamp_us_ = 0;
}

void TrackKalman::predict(double dt_s, Vec4* x, Mat4* P) const {
  // constant velocity per axis; white-acceleration noise Q = q [dt^3/3 dt^2/2; dt^2/2 dt]
  Mat4 f = Mat4::Identity();
  f(0, 1) = dt_s;
  f(2, 3) = dt_s;
  *x = f * *x;
  (*x)(0) = track_.wrap_s((*x)(0));
  const double adt = std::abs(dt_s);
  Mat4 q = Mat4::Zero();
  const double qs = params_.accel_psd_s_m2_s3;
  const double ql = params_.accel_psd_l_m2_s3;
  q(0, 0) = qs * adt * adt * adt / 3.0;
  q(0, 1) = q(1, 0) = qs * adt * adt / 2.0;
  q(1, 1) = qs * adt;
  q(2, 2) = ql * adt * adt * adt / 3.0;
  q(2, 3) = q(3, 2) = ql * adt * adt / 2.0;
  q(3, 3) = ql * adt;
  *P = f * *P * f.transpose() + q;
}

bool TrackKalman::correct(const Eigen::Vector2d& z_enu_m, Vec4* x, Mat4* P) const {
  // world point -> (s, l) on the branch near the prediction (the crossing has two)
  const TrackCoordinates c = track_.project(z_enu_m, (*x)(0), params_.projection_window_m);
  const Eigen::Vector2d innovation(track_.delta_s((*x)(0), c.s_m), c.l_m - (*x)(2));
  Eigen::Matrix<double, 2, 4> h = Eigen::Matrix<double, 2, 4>::Zero();
  h(0, 0) = 1.0;
  h(1, 2) = 1.0;
  const Eigen::Matrix2d r =
      Eigen::Matrix2d::Identity() * params_.measurement_sigma_m * params_.measurement_sigma_m;
  const Eigen::Matrix2d s = h * *P * h.transpose() + r;
  // gate: implausible under the predicted uncertainty, and further than the floor
  if (innovation.norm() > params_.gate_floor_m &&
      innovation.dot(s.ldlt().solve(innovation)) > params_.gate_chi2) {
    return false;
  }
  const Eigen::Matrix<double, 4, 2> k = *P * h.transpose() * s.inverse();
  *x += k * innovation;
  (*x)(0) = track_.wrap_s((*x)(0));
  // Joseph form keeps P symmetric and positive definite
  const Mat4 ikh = Mat4::Identity() - k * h;
  *P = ikh * *P * ikh.transpose() + k * r * k.transpose();
  return true;
}

MeasurementResult TrackKalman::add_measurement(int64_t stamp_us,
                                               const Eigen::Vector2d& position_enu_m) {
  if (!initialised_) {
    // initialise from two points: position and speed along the track (seed 7.1)
    if (!first_point_) {
      first_point_ = {stamp_us, position_enu_m};
      return MeasurementResult::kStored;
    }
    const double dt_s = us_to_s(stamp_us - first_point_->first);
    if (std::abs(dt_s) < params_.init_min_dt_s) return MeasurementResult::kStored;
    if (dt_s < 0.0 || dt_s > params_.init_max_dt_s) {
      first_point_ = {stamp_us, position_enu_m};
      return MeasurementResult::kStored;
    }
    // the branch of the first point whose direction best matches the motion: at the crossing two
    // branches are equally near, but they cross at a wide angle. Branches are judged by their true
    // distance, not |l|: a branch whose closest point is its end (the straight before the
    // crossing, an arc's start) has a small l but lies metres away along the track, and runs
    // parallel to the right branch there; such ties go to the nearer branch (project_all's order).
    const Eigen::Vector2d motion = (position_enu_m - first_point_->second).normalized();
    const std::vector<TrackCoordinates> branches = track_.project_all(first_point_->second);
    constexpr double kBranchSlackM = 3.0;   // candidates this much further than the nearest
    constexpr double kAlignmentTie = 0.05;  // |cos| closer than this: equally aligned
    const auto distance_m = [&](const TrackCoordinates& c) {
      return (track_.point_enu(c.s_m) - first_point_->second).norm();
    };
    const double nearest_m = distance_m(branches.front());
    TrackCoordinates c1 = branches.front();
    double best_alignment = -1.0;
    for (const auto& b : branches) {
      if (distance_m(b) > nearest_m + kBranchSlackM) continue;
      const double alignment = std::abs(track_.tangent_enu(b.s_m).dot(motion));
      if (alignment > best_alignment + kAlignmentTie) {
        best_alignment = alignment;
        c1 = b;
      }
    }
    const TrackCoordinates c2 = track_.project(position_enu_m, c1.s_m, params_.projection_window_m);
    const double v_s = track_.delta_s(c1.s_m, c2.s_m) / dt_s;
    if (std::abs(v_s) > kMaxInitSpeedM_S) {
      first_point_ = {stamp_us, position_enu_m};
      return MeasurementResult::kStored;
    }
    const double var_z = params_.measurement_sigma_m * params_.measurement_sigma_m;
    x_ << c2.s_m, v_s, c2.l_m, 0.0;
    P_ = Mat4::Zero();
    P_(0, 0) = var_z;
    P_(1, 1) = 2.0 * var_z / (dt_s * dt_s);
    P_(0, 1) = P_(1, 0) = var_z / dt_s;  // s2 is shared by the position and the difference
    P_(2, 2) = var_z;
    P_(3, 3) = kInitSigmaVlM_S * kInitSigmaVlM_S;
    stamp_us_ = stamp_us;
    history_.push_back({stamp_us, position_enu_m, x_, P_});
    initialised_ = true;
    first_point_.reset();
    return MeasurementResult::kInitialised;
  }

  if (stamp_us >= stamp_us_) {
    // in order: predict to the image time, correct there
    Vec4 x = x_;
    Mat4 p = P_;
    predict(us_to_s(stamp_us - stamp_us_), &x, &p);
    if (!correct(position_enu_m, &x, &p)) {
      if (++rejections_in_a_row_ < params_.max_rejections) return MeasurementResult::kRejected;
      // the truck is not where the filter thinks: start over from this point
      reset();
      first_point_ = {stamp_us, position_enu_m};
      return MeasurementResult::kRestarted;
    }
    rejections_in_a_row_ = 0;
    x_ = x;
    P_ = p;
    stamp_us_ = stamp_us;
    history_.push_back({stamp_us, position_enu_m, x_, P_});
    while (static_cast<int>(history_.size()) > params_.history_size) history_.pop_front();
    return MeasurementResult::kCorrected;
  }

  // out of order: restart from the newest snapshot not after it, then replay the later measurements
  auto later = std::upper_bound(history_.begin(), history_.end(), stamp_us,
                                [](int64_t t, const Snapshot& s) { return t < s.stamp_us; });
  if (later == history_.begin()) return MeasurementResult::kRejected;  // older than the history
  const Snapshot& base = *std::prev(later);
  Vec4 x = base.x;
  Mat4 p = base.P;
  predict(us_to_s(stamp_us - base.stamp_us), &x, &p);
  if (!correct(position_enu_m, &x, &p)) return MeasurementResult::kRejected;
  std::deque<Snapshot> replay(later, history_.end());
  history_.erase(later, history_.end());
  history_.push_back({stamp_us, position_enu_m, x, p});
  int64_t t_us = stamp_us;
  for (const Snapshot& s : replay) {
    Vec4 xr = x;
    Mat4 pr = p;
    predict(us_to_s(s.stamp_us - t_us), &xr, &pr);
    if (!correct(s.z_enu_m, &xr, &pr)) continue;  // an outlier now: leave it out
    x = xr;
    p = pr;
    t_us = s.stamp_us;
    history_.push_back({s.stamp_us, s.z_enu_m, x, p});
  }
  x_ = x;
  P_ = p;
  stamp_us_ = t_us;
  while (static_cast<int>(history_.size()) > params_.history_size) history_.pop_front();
  return MeasurementResult::kReordered;
}

TrackEstimate TrackKalman::make_estimate(int64_t stamp_us, const Vec4& x, const Mat4& P) const {
  TrackEstimate e;
  e.stamp_us = stamp_us;
  e.s_m = x(0);
  e.v_s_m_s = x(1);
  e.l_m = x(2);
  e.v_l_m_s = x(3);
  e.position_enu_m = track_.point_enu(TrackCoordinates{x(0), x(2)});
  const Eigen::Vector2d t = track_.tangent_enu(x(0));
  const Eigen::Vector2d n(-t.y(), t.x());
  // a point at offset l on a curve of curvature k moves (1 - k l) times as fast as its projection
  e.velocity_enu_m_s = x(1) * (1.0 - track_.curvature_1_m(x(0)) * x(2)) * t + x(3) * n;
  e.sigma_s_m = std::sqrt(std::max(P(0, 0), 0.0));
  e.sigma_l_m = std::sqrt(std::max(P(2, 2), 0.0));
  return e;
}

std::optional<TrackEstimate> TrackKalman::estimate_at(int64_t stamp_us) const {
  if (!initialised_) return std::nullopt;
  // extrapolate with the motion model along the track (kinematics, seed 7.1)
  Vec4 x = x_;
  Mat4 p = P_;
  predict(us_to_s(stamp_us - stamp_us_), &x, &p);
  return make_estimate(stamp_us, x, p);
}

std::optional<Interception> TrackKalman::intercept(int64_t now_us,
                                                   const Eigen::Vector2d& uav_position_enu_m,
                                                   double uav_speed_m_s, double horizon_s) const {
  if (!initialised_ || !(uav_speed_m_s > 0.0)) return std::nullopt;
  // the state mean at now_us (the covariance plays no part in the meeting point)
  const double dt_s = us_to_s(now_us - stamp_us_);
  Vec4 x_now = x_;
  x_now(0) += x_now(1) * dt_s;
  x_now(2) += x_now(3) * dt_s;
  // gap(tau) = |truck(tau) - uav| - v tau; the first sign change is the earliest meeting
  auto truck_at = [&](double tau_s) {
    const double s = x_now(0) + x_now(1) * tau_s;
    const double l = x_now(2) + x_now(3) * std::min(tau_s, params_.lateral_extrapolation_limit_s);
    return track_.point_enu(TrackCoordinates{s, l});
  };
  auto gap = [&](double tau_s) {
    return (truck_at(tau_s) - uav_position_enu_m).norm() - uav_speed_m_s * tau_s;
  };
  constexpr double kStepS = 0.1;
  double lo = 0.0;
  if (gap(lo) <= 0.0) return Interception{0.0, truck_at(0.0), track_.wrap_s(x_now(0))};
  for (double hi = kStepS; hi <= horizon_s; lo = hi, hi += kStepS) {
    if (gap(hi) > 0.0) continue;
    // bisect the bracket to about a millisecond
    for (int i = 0; i < 20; ++i) {
      const double mid = 0.5 * (lo + hi);
      (gap(mid) > 0.0 ? lo : hi) = mid;
    }
    return Interception{hi, truck_at(hi), track_.wrap_s(x_now(0) + x_now(1) * hi)};
  }
  return std::nullopt;
}

}  // namespace uavsim::vision
