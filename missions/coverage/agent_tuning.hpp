// The coverage agent's tuning: its timeouts, gains and distances, shared by agent.cpp (the
// agent's machinery) and agent_states.cpp (its state handlers). Internal to the agent: include it
// from those two files only.
#pragma once

#include <string>

#include "uavsim/common/fmt.hpp"

namespace uavsim::missions::coverage::agent_tuning {

// Taking Off lasts at least this long, so the ADB has heard the flock before the roles are chosen
inline constexpr double kDiscovery_s = 3.0;
// a leader query that has not completed in this long is started again (an agent it waited for
// may have failed after being counted live; the ADB will have dropped it by then)
inline constexpr double kQueryTimeout_s = 20.0;
// Waiting ends at the latest after this long
inline constexpr double kWaitTimeout_s = 30.0;
// a pass that added less than this fraction of the rectangle made no progress
inline constexpr double kNoProgressFraction = 1e-3;
// the leader is at the start of its path when this close
inline constexpr double kAtStart_m = 1.5;
// a pass starts when neighbours' footprints overlap at least this much across the line: a flock
// that has just deployed a swath sideways trails out (25 quads over 600 x 600 m, seed 3: two
// neighbours 10.7 m apart for the first 20 m of a pass, slivers left between 10 m footprints and a
// repair pass at the end, 100 s)
inline constexpr double kMinFootprintOverlap_m = 1.0;
// Running: the leader aims at its path this far ahead, and corrects sideways with this gain
inline constexpr double kLookahead_m = 5.0;
inline constexpr double kLateralGain_1_s = 0.5;
// The share of the radio's airtime an agent gives its aggregation frames, and the airtime they
// may take at once after a pause (radio_pacer.hpp): 23 full frames, so a short message goes out
// whole at once and a beacon waits at most ~0.1 s behind a long one (0.8 m at the deploy's 8 m/s).
// The beacons themselves take 8 x 4.3 ms a second (3.4 %).
inline constexpr double kAggregateAirtimeShare = 0.75;
inline constexpr double kAggregateBurst_s = 0.1;
// altitude hold and home approach
inline constexpr double kAltitudeGain_1_s = 1.0;
inline constexpr double kMaxClimb_m_s = 2.0;
inline constexpr double kApproachGain_1_s = 0.5;
inline constexpr double kHomeReached_m = 1.0;
// ... and stays home (hovering over it or landing) until it drifts this far: the leader, hovering
// 3 m over its home while the others landed, drifted 1.03 m off, took itself for away, climbed
// back to its layer and landed 16 s late (25 quads over 600 x 600 m, seed 4)
inline constexpr double kHomeLeft_m = 3.0;
// the last metres home: the speed falls with the distance left (1 m/s a metre), twice as steep as
// kApproachGain_1_s: nothing is photographed here, so only stopping at home matters; and before
// that, no faster than a quad braking at kHomeBraking_m_s2 can stop at home (from 12 m/s, the
// linear profile alone asked for 12 m/s2 and the leader overshot its home by 20 m)
inline constexpr double kHomeApproachGain_1_s = 1.0;
inline constexpr double kHomeBraking_m_s2 = 2.5;
// Going Home: agents of the same altitude layer closer than this push each other apart
inline constexpr double kHomeSeparation_m = 5.0;
inline constexpr double kHomeSeparationSpeed_m_s = 1.5;
// Going Home after a loss: once agents have landed, the leader checks the flock's map only this
// close to its home, where the landed agents (on the take-off line, radios on) answer its query
inline constexpr double kVerifyNearHome_m = 50.0;
// a landed agent that noticed a loss stays on this long for the leader's check (its query, answered
// by every landed agent, takes a few seconds; kQueryTimeout_s per retry)
inline constexpr double kLossWait_s = 2.0 * kQueryTimeout_s;
// Running: an agent lost in the line leaves its strip open from where it died until its neighbours
// have closed the gap (15 m wide, closed at up to 1 m/s: 17 m of track, 25 quads over 600 x 600 m,
// seed 1, p 0.001). Where the strip lies further than the planner's lateral threshold from either
// edge of the flock, no next pass bends over it, and the last query sent the whole flock back for
// it (84 s, 58 s of transit). The leader hears of the loss when the record ages out, up to the age
// allowed for its distance after the death; so it holds the flock until the line has closed (at
// most kRewindHold_s), flies back along the path by that age at the cruise speed plus
// kRewindMargin_m, and runs the stretch again (that run: 680.1 s instead of 746.8 s). Nearer an
// edge, the next pass on that side covers the strip anyway, and the rewind only cost time (5 quads
// over 150 x 100 m: +15 s).
inline constexpr double kRewindHold_s = 20.0;
inline constexpr double kRewindMargin_m = 5.0;
// the station's map counts as arriving when the last came this recently (it changes, and is sent,
// every second or so while the flock takes pictures)
inline constexpr double kStationMapFresh_s = 5.0;
// the leader's hover over its home while the others land (it lands last)
inline constexpr double kLeaderWaitAltitude_m = 3.0;

using common::fmt;  // the log lines' numbers

}  // namespace uavsim::missions::coverage::agent_tuning
