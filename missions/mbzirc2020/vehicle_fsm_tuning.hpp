// The balloon UAV's tuning: its gains, distances and times, shared by vehicle_fsm.cpp (the
// machine), vehicle_states.cpp (its states up to Back Off) and vehicle_landing.cpp (Land).
// Internal to the state machine: include it from those files only.
#pragma once

#include <cstdio>
#include <string>

#include "uavsim/common/angles.hpp"
#include "uavsim/common/fmt.hpp"

namespace uavsim::missions::mbzirc2020::vehicle_tuning {

using common::kPi;

inline constexpr double kGainXy_1_s = 1.0;       // position error -> horizontal speed
inline constexpr double kGainZ_1_s = 1.5;        // altitude error -> climb rate
inline constexpr double kFreshSighting_s = 0.5;  // a sighting older than this is "lost"
inline constexpr double kSameBalloon_m = 1.5;  // a new track this close to the target is the target
inline constexpr double kPoppedExclusion_m = 2.5;
// The poles of the balloons we popped still stand: a pierce whose path ahead passes closer than
// this to one flies over its top (backoff_above_centre_m over its balloon's centre, as the back off
// does) until past it. Two-UAV field seed 8: drifting sideways into a pierce of b0 (2.5 m high),
// the line from here to b0 swung through the pole of b3, popped earlier, whose top is at 2.7 m;
// the hull hit it at 3.5 m/s. The popped place is our estimate then (GPS drift ~0.5 m since), the
// hull reaches ~0.4 m out.
inline constexpr double kPoleClearance_m = 1.5;
// A balloon seen this close to a pierce's path, nearer than its target, is in the way: the
// pierce takes it instead (one-UAV field seed 12: a pierce of b3, 36 m away, flew through b0,
// 10 m in front and straight on the line, at 3 m/s; the hull hit it). The hull reaches ~0.4 m
// out, the balloon's radius is 0.3 m, and the estimates are a few tenths off.
inline constexpr double kInTheWay_m = 1.2;
inline constexpr double kArenaMargin_m = 0.5;
// a balloon seen further above or below is a bad estimate
inline constexpr double kMaxPierceClimb_m = 1.5;
// The heading setpoint turns at most this fast. The flight controller's mixer kept yaw torque
// before collective thrust (it now leaves yaw only a headroom, as ArduCopter does): a setpoint that
// jumped by 90-180 deg saturated it and the vehicle sank. Field seed 20 (two UAVs): backing off
// past a balloon it had missed by 1.6 m, the heading to the balloon swung through 140 deg in 3 s;
// the UAV sank from 3.4 m into the ground at 3.1 m/s while commanded to climb.
inline constexpr double kMaxYawRate_rad_s = 1.0;
inline constexpr double kBackOffFaceBalloon_m = 3.0;
// A pierce whose target has turned further than this from where it pointed at the start is not
// going through that balloon: one-UAV field seed 6 turned through 130 deg towards another balloon
// 6.7 m away as the target's track drifted at close range (a balloon cut by the image's edge reads
// too far), and met that balloon's pole.
inline constexpr double kPierceMaxTurn_rad = 60.0 * kPi / 180.0;
// the landing spot is approached so that the vehicle can stop there at this deceleration; the
// descent starts only once it is (almost) still: braking from 5-6 m/s while descending, the
// controller's vertical loop gave way (one-UAV field seeds 8 and 9: 2.7 m/s sink from 4.5 m, roll
// 19 deg)
inline constexpr double kLandingApproachDecel_m_s2 = 1.5;
inline constexpr double kLandingStillSpeed_m_s = 0.5;
inline constexpr double kLandingPauseClimb_m_s =
    0.3;  // the last 2 m paused for a gust (touchdown_gate)
// over the spot, the lean is read this long before the heading turns the skids along the wind,
// and the descent starts once they are within kLandingSkidAlign_rad of it (or after
// kLandingAlignMax_s whatever the heading)
inline constexpr double kLandingWindRead_s = 2.0;
inline constexpr double kLandingSkidAlign_rad = 10.0 * kPi / 180.0;
inline constexpr double kLandingAlignMax_s = 10.0;
// A pierce whose blades reached the balloon's estimate reports POPPED only after this long back on
// the line facing where the balloon was, a sighting within kSeenAgain_m of it meaning it is still
// there: whether the camera lost the balloon at close range or the blades went past the estimate
// with the balloon unseen (two-UAV field seed 7, one-UAV seed 3: the blades passed 0.7 m beside a
// 0.3 m balloon, truth, and it was counted popped). Two-UAV field seeds 2 and 5: the
// balloon, 4 m in front of the line and 3.0-3.1 m high, seen 0.8-1.1 m from where it was; the
// blades reached the estimate, not the balloon; the back off climbed over it (out of the 5 deg
// down camera's view within 3 m) and was over in 2 s, and the balloon was reported popped, its
// true place then excluded from targets as a popped balloon's.
inline constexpr double kLookBack_s = 2.5;
inline constexpr double kSeenAgain_m = 2.0;

using common::fmt;  // the state machine's log lines

}  // namespace uavsim::missions::mbzirc2020::vehicle_tuning
