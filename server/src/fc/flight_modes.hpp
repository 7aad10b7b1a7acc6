// One object per ArduCopter flight mode, over the mode context (ModeContext, mode_context.hpp: the
// estimate, time, parameters and home read-only; the cascade command, the yaw and the carrot it
// sets; GUIDED's targets, the mission and the services every mode flies with — run_nav, start_hold,
// start_takeoff, run_land_descent, the pilot's sticks). A mode never sees the flight controller's
// private state: the failsafes, mixers, sensors, battery, link and arming are out of its reach, so
// a test can drive a mode over a context it builds itself. A mode keeps its own state (BRAKE's
// latch, RTL's stage, AUTO's phase) and says what it needs and allows; enter() sets it up when the
// vehicle is armed (flying or not), update() asks the cascade for one control step while the
// vehicle is off the ground (or taking off), and exit() runs when another mode takes over. The
// shared rules (the modes' common entry resets, the idle on the ground, auto-disarm) stay in
// modes.cpp.
#pragma once

#include <cstdint>

#include "fc/fc_types.hpp"

namespace uavsim::server::fc {

class ModeContext;

class FlightMode {
 public:
  virtual ~FlightMode() = default;
  virtual Mode id() const = 0;

  // ArduCopter's requires_GPS: refused without a converged position estimate
  virtual bool needs_position() const { return false; }
  // ArduCopter's allows_arming: the modes a vehicle may be armed in
  virtual bool allows_arming() const { return false; }
  // the pilot's sticks (RC overrides) are read in this mode
  virtual bool reads_pilot() const { return false; }
  // on the ground (and not taking off) the vehicle disarms at once instead of after DISARM_DELAY
  virtual bool disarms_when_landed() const { return false; }
  // descending to land now (EXTENDED_SYS_STATE's LANDING)
  virtual bool landing() const { return false; }
  // a touchdown now ends the flight: the vehicle disarms
  virtual bool ends_flight_at_touchdown() const { return false; }

  virtual void enter(ModeContext& c, bool flying) {
    (void)c;
    (void)flying;
  }
  virtual void update(ModeContext& c, double dt_s) = 0;
  virtual void exit(ModeContext& c) { (void)c; }
};

class StabilizeMode final : public FlightMode {
 public:
  Mode id() const override { return Mode::kStabilize; }
  bool allows_arming() const override { return true; }
  bool reads_pilot() const override { return true; }
  void enter(ModeContext& c, bool flying) override;
  void update(ModeContext& c, double dt_s) override;
};

class AltHoldMode final : public FlightMode {
 public:
  Mode id() const override { return Mode::kAltHold; }
  bool allows_arming() const override { return true; }
  bool reads_pilot() const override { return true; }
  void update(ModeContext& c, double dt_s) override;
};

class GuidedMode final : public FlightMode {
 public:
  Mode id() const override { return Mode::kGuided; }
  bool needs_position() const override { return true; }
  bool allows_arming() const override { return true; }
  void enter(ModeContext& c, bool flying) override;
  void update(ModeContext& c, double dt_s) override;
};

class LoiterMode final : public FlightMode {
 public:
  Mode id() const override { return Mode::kLoiter; }
  bool needs_position() const override { return true; }
  bool allows_arming() const override { return true; }
  bool reads_pilot() const override { return true; }
  void enter(ModeContext& c, bool flying) override;
  void update(ModeContext& c, double dt_s) override;
};

class BrakeMode final : public FlightMode {
 public:
  Mode id() const override { return Mode::kBrake; }
  bool needs_position() const override { return true; }
  void enter(ModeContext& c, bool flying) override;
  void update(ModeContext& c, double dt_s) override;

 private:
  bool holding_ = false;  // stopped: holding the position where it stopped
};

class LandMode final : public FlightMode {
 public:
  Mode id() const override { return Mode::kLand; }
  bool disarms_when_landed() const override { return true; }
  bool landing() const override { return true; }
  bool ends_flight_at_touchdown() const override { return true; }
  void enter(ModeContext& c, bool flying) override;
  void update(ModeContext& c, double dt_s) override;
};

// RTL: climb to RTL_ALT, return, loiter RTL_LOIT_TIME over home, land. AUTO's RTL items run it too.
class RtlMode final : public FlightMode {
 public:
  Mode id() const override { return Mode::kRtl; }
  bool needs_position() const override { return true; }
  bool disarms_when_landed() const override { return true; }
  bool landing() const override { return stage_ == Stage::kLand; }
  bool ends_flight_at_touchdown() const override { return true; }
  void enter(ModeContext& c, bool flying) override;
  void update(ModeContext& c, double dt_s) override;
  // starts the return from where the vehicle is
  void start(ModeContext& c);

 private:
  enum class Stage { kClimb, kReturn, kLoiter, kLand };
  Stage stage_ = Stage::kClimb;
  double loiter_start_s_ = 0.0;
  double alt_enu_m_ = 0.0;
};

// AUTO: the mission's items in turn (item 0 is home).
class AutoMode final : public FlightMode {
 public:
  explicit AutoMode(RtlMode& rtl) : rtl_(rtl) {}
  Mode id() const override { return Mode::kAuto; }
  bool needs_position() const override { return true; }
  bool landing() const override {
    return phase_ == Phase::kLandDescend || (phase_ == Phase::kRtl && rtl_.landing());
  }
  bool ends_flight_at_touchdown() const override {
    return phase_ == Phase::kLandDescend || phase_ == Phase::kRtl;
  }
  void enter(ModeContext& c, bool flying) override;
  void update(ModeContext& c, double dt_s) override;
  // starts mission item seq (past the end, or past MISSION_START's last item: mission complete,
  // hold)
  void start_item(ModeContext& c, int seq);
  // the current item is reached: MISSION_ITEM_REACHED, then the next one
  void complete_item(ModeContext& c);
  // the mission is over (it landed)
  void finish() { phase_ = Phase::kDone; }

 private:
  enum class Phase { kNav, kHold, kLandApproach, kLandDescend, kRtl, kYaw, kDone };
  RtlMode& rtl_;
  Phase phase_ = Phase::kDone;
  double hold_start_s_ = 0.0;
};

// Every mode, one object each, and the one for a mode number.
struct FlightModes {
  StabilizeMode stabilize;
  AltHoldMode alt_hold;
  GuidedMode guided;
  LoiterMode loiter;
  BrakeMode brake;
  LandMode land;
  RtlMode rtl;
  AutoMode automatic{rtl};

  FlightModes() = default;
  FlightModes(const FlightModes&) = delete;
  FlightModes& operator=(const FlightModes&) = delete;

  FlightMode& of(Mode mode);
  const FlightMode& of(Mode mode) const { return const_cast<FlightModes*>(this)->of(mode); }
};

}  // namespace uavsim::server::fc
