// Camera gimbals: a camera sits in a small kinematic (mocap) body that follows its vehicle's camera mount
// and is oriented every step independently of the vehicle's attitude (a stabilised 2-axis gimbal):
// "down" looks straight down, "forward" looks level along the vehicle's heading, "targets" points at a
// pitch and a yaw (relative to the heading) that MAVLink gimbal commands or the API set.
//
// World file: a mocap body holding the camera, and a custom text binding it to a vehicle:
//   <body name="uav0_gimbal" mocap="true"><camera name="uav0_cam" xyaxes="0 -1 0 0 0 1" .../></body>
//   <text name="uavsim:gimbal:uav0_gimbal" data="uav0 down"/>          (mode: down | forward | targets)
// The gimbal body's x axis is the pointing direction; a camera with xyaxes="0 -1 0 0 0 1" looks along
// it with the image top up. The mount is an offset in the vehicle's body frame after the mode
// (data="uav0 down 0 0 -0.09"), else the vehicle's site VEHICLE/camera_mount, else its origin.
//
// Field conditions give the gimbal dynamics (sim::GimbalDynamicsParams): the camera is carried by the
// vehicle and the stabilisation loop slews it back to its target at error / time constant, limited in
// rate and acceleration, so a fast manoeuvre tilts the view for a moment. Time constant 0: perfect.
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

#include "sim/simulation.hpp"

namespace uavsim::server::objects {

enum class GimbalMode { kDown, kForward, kTargets };

// The stabilisation loop's state: where the camera points relative to the vehicle body, and how fast it
// slews there.
struct GimbalMotion {
  Eigen::Quaterniond q_body_cam = Eigen::Quaterniond::Identity();
  Eigen::Vector3d rate_body_rad_s = Eigen::Vector3d::Zero();
  bool started = false;   // false: the next step starts on target
  double time_s = 0.0;    // sim time of the last step
};

// (target orientation in the body frame, dt) => the camera's orientation after dt: slew rate
// error / time_const_s (rotation vector), at most rate_max, changed by at most accel_max * dt (limits 0:
// none). Without limits the pointing error decays as exp(-t / time_const_s).
void step_gimbal_motion(const sim::GimbalDynamicsParams& params, const Eigen::Quaterniond& q_body_target,
                        double dt_s, GimbalMotion* motion);
const char* gimbal_mode_name(GimbalMode mode);

struct Gimbal {
  std::string name;   // the gimbal body
  int vehicle = -1;
  int body_id = -1;
  Eigen::Vector3d mount_body_m = Eigen::Vector3d::Zero();  // in the vehicle's body frame
  GimbalMode mode = GimbalMode::kDown;
  double pitch_rad = 0.0;  // kTargets: up positive, -pi/2 = straight down (MAVLink's sign)
  double yaw_rad = 0.0;    // kTargets: relative to the vehicle's heading, counter-clockwise positive
  GimbalMotion motion;     // with dynamics (field conditions)
};

class GimbalSet : public sim::WorldObject {
 public:
  explicit GimbalSet(std::vector<Gimbal> gimbals, const sim::GimbalDynamicsParams& dynamics = {})
      : gimbals_(std::move(gimbals)), dynamics_(dynamics) {}

  // Steps the stabilisation loop (with dynamics), then place().
  void before_step(sim::Simulation& sim) override;
  // Puts every gimbal body at its vehicle's mount as the vehicle is now, oriented as the gimbal is
  // now; steps nothing. Loop thread only.
  void place(sim::Simulation& sim) const;
  // Registers place() first in the capture phase, so camera snapshots see the gimbals at the
  // vehicles' pose of the snapshot's instant, not the pose before the last physics step. It only
  // places bodies (no loop step), so whether a snapshot is taken or dropped never changes the motion.
  void schedule_capture_pose(sim::Simulation& sim);
  bool on_contact(sim::Simulation&, const physics::VehicleContact&) override { return false; }
  void reset(uint64_t seed) override;

  // The gimbals, for pointing commands (set mode, pitch_rad, yaw_rad). Loop thread only.
  std::vector<Gimbal>& gimbals() { return gimbals_; }
  const std::vector<Gimbal>& gimbals() const { return gimbals_; }
  // The orientation a gimbal's body takes for a vehicle heading (ENU yaw), from its mode and targets.
  static Eigen::Quaterniond pointing(const Gimbal& gimbal, double vehicle_yaw_rad);
  // The orientation the gimbal body has now (ENU), after its dynamics. Loop thread only.
  static Eigen::Quaterniond actual(const Gimbal& gimbal, const Eigen::Quaterniond& q_enu_body);
  // The orientation the gimbal body takes on a vehicle of attitude q_enu_body: actual() once its
  // loop has stepped (with dynamics), else pointing(). What place() gives the body and a camera
  // sees.
  static Eigen::Quaterniond orientation(const Gimbal& gimbal, const Eigen::Quaterniond& q_enu_body);
  // The heading (ENU yaw) of a vehicle attitude: where its body x axis points, seen from above.
  static double heading(const Eigen::Quaterniond& q_enu_body);
  const sim::GimbalDynamicsParams& dynamics() const { return dynamics_; }

 private:
  // one gimbal body at its vehicle's mount, the vehicle's truth given
  static void place(sim::Simulation& sim, const Gimbal& gimbal, const fc::TruthState& truth);
  std::vector<Gimbal> gimbals_;
  sim::GimbalDynamicsParams dynamics_;
  std::vector<Gimbal> initial_;
  bool initial_saved_ = false;
};

}  // namespace uavsim::server::objects
