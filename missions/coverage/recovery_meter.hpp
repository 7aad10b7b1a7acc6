// Table 4.3's quantity, "distance flown to recover from failed agents", measured by the launcher
// from the agents' APD reports (scoring only: no agent sees it). The pictures a failed agent held
// that nobody alive (nor the ground station) holds are lost ground. A live agent that photographs
// lost ground again is recovering: for each stripe its report adds anew, the stripe's length along
// x (the flight that photographs it) times the share of the new interval that was lost. An agent
// flying beside it over new ground recovers nothing, so this is the flock's flight spent on
// recovery, not the whole passes that carry it (the launcher also reports the total distance, from
// which a sweep takes the extra distance against a failure-free run). From the pictures, not from
// the distance between reports: an agent reports only when its APD changed, so its first report
// after a transit would carry the whole transit. Pure: no clocks, no I/O.
#pragma once

#include <map>
#include <vector>

#include "area_parts.hpp"

namespace uavsim::missions::coverage {

// The parts of normal-form list `a` outside normal-form list `b`, and inside it.
std::vector<Interval> stripe_minus(const std::vector<Interval>& a, const std::vector<Interval>& b);
std::vector<Interval> stripe_and(const std::vector<Interval>& a, const std::vector<Interval>& b);

class RecoveryMeter {
 public:
  // The rectangle's stripes, its width along y and its length along x.
  RecoveryMeter(int stripes, double width_m, double length_m);

  // An agent's APD report (its own pictures). Reports with another stripe count are ignored.
  void agent_report(int agent, const AreaParts& apd);
  // The ground station's map (the optimised variant): what it holds is not lost when an agent
  // fails; it flies nothing, so it recovers nothing.
  void station_report(const AreaParts& map);
  // The agent was killed or crashed: what it alone held is lost from now on. Returns that share
  // of the rectangle (0 if the agent had failed already).
  double agent_failed(int agent);

  // Distance flown to recover lost ground, all agents together [m].
  double distance_m() const { return distance_m_; }
  // Share of the rectangle photographed again after it was lost (stripes weigh the same, as the
  // scoring's covered fraction); ground lost and recovered twice counts twice.
  double recovered_fraction() const;
  // Share of the rectangle lost now (not recovered yet).
  double lost_fraction() const;
  // Share of the rectangle lost at the failures, all together (ground lost, recovered and lost
  // again counts twice). Without a station this is the floor of the recovery: the flock cannot
  // photograph less again than what died with its agents.
  double lost_at_failures_fraction() const;

 private:
  struct Holder {
    AreaParts apd;
    bool failed = false;
  };
  // The agent's entry (an empty APD, live, when first seen).
  Holder& holder(int agent);
  // Per stripe: what the live agents and the station hold.
  std::vector<Interval> held(int stripe) const;
  // Adds to the lost ground what `apd` holds that nobody alive holds; returns its summed length.
  double lose(const AreaParts& apd);
  // Summed interval length over stripes -> share of the rectangle.
  double fraction(double length_m) const;

  int stripes_;
  double width_m_;
  double stripe_length_m_;
  std::map<int, Holder> agents_;
  AreaParts station_;
  AreaParts lost_;
  double distance_m_ = 0.0;
  double recovered_m_ = 0.0;  // summed interval length over stripes
  double lost_m_ = 0.0;       // the same, lost at failures
};

}  // namespace uavsim::missions::coverage
