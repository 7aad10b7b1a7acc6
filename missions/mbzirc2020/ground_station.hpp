// The ground station's part of the balloon mission (seed 7.2), as a pure class: it starts the UAVs,
// allocates airspace, notices a failed UAV and hands its side to the others, re-tasks a UAV whose
// own scans are done while balloons remain to the other half, and lands everyone once the five
// balloons are reported popped. The UDP/event-loop shell is gcs_main.cpp.
//
// Airspace (seed 7.2, note 40): "The ground control software receives AIRSPACE messages from both
// UAVs and, therefore, knows if they are trying to get too close. If they are sufficiently apart,
// it replies to both. Otherwise, it only replies to the first one and the other one has to wait." A
// request is the segment from the UAV to the end of its pierce; it is granted (echoed unchanged)
// when it stays min_separation_m away from every other UAV's granted segment and from every other
// flying UAV's last reported position. NaN releases.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "messages.hpp"

namespace uavsim::missions::mbzirc2020 {

struct GroundStationConfig {
  int balloon_count = 5;          // rules: five balloons
  double min_separation_m = 5.0;  // between allocated airspace segments / flying UAVs
  double stale_s = 3.0;           // no STATUS for this long after start: the UAV is out
  double start_timeout_s = 60.0;  // start the ready UAVs even if some never got ready
  double popped_merge_m = 2.5;    // reports closer than this are one balloon
};

struct GcsOutgoing {
  int uav = 0;
  uint16_t topic = 0;
  std::vector<uint8_t> payload;
};

// Distance between segments [a0, a1] and [b0, b1] in the plane.
double segment_distance(const Eigen::Vector2d& a0, const Eigen::Vector2d& a1,
                        const Eigen::Vector2d& b0, const Eigen::Vector2d& b1);

class GroundStation {
 public:
  GroundStation(const GroundStationConfig& config, int uav_count);

  // Messages from UAV `uav` (loop time now_s).
  void on_status(int uav, const UavStatus& s, double now_s);
  void on_airspace(int uav, const std::optional<AirspaceArea>& a, double now_s);
  void on_popped(int uav, const Eigen::Vector2d& p_enu_m, double now_s);

  // (time) => messages to send; notes get a line for each decision.
  std::vector<GcsOutgoing> step(double now_s, std::vector<std::string>* notes);

  bool started() const { return started_; }
  // started and every UAV has landed or is out
  bool finished() const;
  int popped_reported() const { return static_cast<int>(popped_.size()); }
  const std::optional<AirspaceArea>& granted(int uav) const { return uavs_[uav].granted; }

 private:
  struct Uav {
    bool heard = false;
    UavStatus status;
    double last_status_s = -1.0;
    bool out = false;
    bool take_over_sent = false;
    bool retask_sent = false;
    std::optional<AirspaceArea> pending;  // requested, not yet granted
    double pending_since_s = 0.0;
    std::optional<AirspaceArea> granted;
  };
  bool conflicts(int uav, const AirspaceArea& a) const;

  GroundStationConfig config_;
  std::vector<Uav> uavs_;
  bool started_ = false;
  double first_heard_s_ = -1.0;
  bool land_sent_ = false;
  std::vector<Eigen::Vector2d> popped_;
  std::vector<GcsOutgoing> queued_;
  std::vector<std::string> queued_notes_;
};

}  // namespace uavsim::missions::mbzirc2020
