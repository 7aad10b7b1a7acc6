// Kalman filter for the truck on the eight-shaped track (seed 7.1, fig. 7.5): state (s, v_s, l,
// v_l), the arc length along the expected path, its rate, the lateral offset and its rate.
// Measurements are world positions of the marker tied to the image's timestamp; they arrive late
// (image processing latency), so the filter predicts to the image time, corrects there, and
// extrapolates to "now" on request ("delayed time horizon", seed 7.1). Measurements that arrive out
// of order are handled by re-running the filter from a stored snapshot.
//
// Constant-velocity model per axis with white-acceleration process noise (Bar-Shalom, Li,
// Kirubarajan 2001, sec. 6.3.2): F = [1 dt; 0 1], Q = q [dt^3/3 dt^2/2; dt^2/2 dt].
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <deque>
#include <optional>

#include "uavsim/vision/eight_track.hpp"

namespace uavsim::vision {

struct TrackKalmanParams {
  double measurement_sigma_m = 0.3;  // per axis, of a marker position
  double accel_psd_s_m2_s3 = 0.05;   // q along the track (speed changes are rare and slow)
  double accel_psd_l_m2_s3 = 0.01;   // q across it (the driver keeps to the path)
  double init_max_dt_s = 2.0;        // two initial detections further apart do not initialise
  // nor closer ones: at 15 km/h, 0.4 s is 1.7 m, enough for the direction of motion to pick the
  // branch at the crossing against 0.3 m noise
  double init_min_dt_s = 0.4;
  double projection_window_m = 15.0;  // branch choice near the crossing, see EightTrack::project
  // outlier gate on the innovation's Mahalanobis distance squared (chi-square, 2 dof: 18.4 is
  // p = 1e-4), never tighter than gate_floor_m; after max_rejections in a row the filter restarts
  // from the next two points rather than ignore a truck that really went elsewhere
  double gate_chi2 = 18.4;
  double gate_floor_m = 1.5;
  int max_rejections = 5;
  int history_size = 32;  // snapshots kept for out-of-order measurements
  // intercept() extrapolates the lateral rate for at most this long: weaving is not a trend
  double lateral_extrapolation_limit_s = 1.0;
};

// Filter state at one time.
struct TrackEstimate {
  int64_t stamp_us = 0;
  double s_m = 0.0;
  double v_s_m_s = 0.0;
  double l_m = 0.0;
  double v_l_m_s = 0.0;
  Eigen::Vector2d position_enu_m = Eigen::Vector2d::Zero();
  Eigen::Vector2d velocity_enu_m_s = Eigen::Vector2d::Zero();
  double sigma_s_m = 0.0;  // 1-sigma of s
  double sigma_l_m = 0.0;  // 1-sigma of l
};

// Where and when a UAV flying straight at constant speed first meets the truck.
struct Interception {
  double time_to_go_s = 0.0;
  Eigen::Vector2d point_enu_m = Eigen::Vector2d::Zero();
  double s_m = 0.0;
};

enum class MeasurementResult {
  kStored,       // first point, waiting for a second to initialise
  kInitialised,  // second point: the filter started
  kCorrected,
  kReordered,  // older than the newest measurement: the filter was re-run from a snapshot
  kRejected,   // outlier (gate), or too old for the history
  kRestarted,  // too many outliers in a row: this point is the first of a new initialisation
};

// Not thread-safe: one owner (the mission's vision/estimation thread).
class TrackKalman {
 public:
  TrackKalman(const EightTrack& track, const TrackKalmanParams& params = {});

  // Adds a marker position measured in the image taken at stamp_us (sim time).
  MeasurementResult add_measurement(int64_t stamp_us, const Eigen::Vector2d& position_enu_m);

  bool initialised() const { return initialised_; }

  // The estimate extrapolated (or interpolated from the last correction) to stamp_us; nullopt until
  // initialised. Extrapolation follows the track's curve, which is why s is a state.
  std::optional<TrackEstimate> estimate_at(int64_t stamp_us) const;

  // The earliest meeting point of the truck (extrapolated from now_us) and a UAV at
  // uav_position_enu_m flying at uav_speed_m_s, within horizon_s; nullopt if not initialised or
  // unreachable.
  std::optional<Interception> intercept(int64_t now_us, const Eigen::Vector2d& uav_position_enu_m,
                                        double uav_speed_m_s, double horizon_s = 120.0) const;

  void reset();

 private:
  using Vec4 = Eigen::Matrix<double, 4, 1>;
  using Mat4 = Eigen::Matrix<double, 4, 4>;
  struct Snapshot {  // posterior after a measurement, and the measurement itself for re-runs
    int64_t stamp_us;
    Eigen::Vector2d z_enu_m;
    Vec4 x;
    Mat4 P;
  };

  void predict(double dt_s, Vec4* x, Mat4* P) const;
  bool correct(const Eigen::Vector2d& z_enu_m, Vec4* x, Mat4* P) const;
  TrackEstimate make_estimate(int64_t stamp_us, const Vec4& x, const Mat4& P) const;

  EightTrack track_;
  TrackKalmanParams params_;
  bool initialised_ = false;
  std::optional<std::pair<int64_t, Eigen::Vector2d>> first_point_;
  int64_t stamp_us_ = 0;  // time of x_, P_ (the newest measurement)
  Vec4 x_ = Vec4::Zero();
  Mat4 P_ = Mat4::Zero();
  std::deque<Snapshot> history_;
  int rejections_in_a_row_ = 0;
};

}  // namespace uavsim::vision
