#include "recovery_meter.hpp"

#include <algorithm>

namespace uavsim::missions::coverage {

std::vector<Interval> stripe_minus(const std::vector<Interval>& a, const std::vector<Interval>& b) {
  std::vector<Interval> out;
  size_t j = 0;
  for (Interval rest : a) {
    // skip the parts of b wholly below this interval; both lists are sorted and disjoint
    while (j < b.size() && b[j].end_m <= rest.start_m) ++j;
    for (size_t k = j; k < b.size() && b[k].start_m < rest.end_m; ++k) {
      if (b[k].start_m > rest.start_m) out.push_back({rest.start_m, b[k].start_m});
      rest.start_m = std::max(rest.start_m, b[k].end_m);
    }
    if (rest.end_m > rest.start_m) out.push_back(rest);
  }
  return out;
}

std::vector<Interval> stripe_and(const std::vector<Interval>& a, const std::vector<Interval>& b) {
  std::vector<Interval> out;
  size_t i = 0, j = 0;
  while (i < a.size() && j < b.size()) {
    const double lo = std::max(a[i].start_m, b[j].start_m);
    const double hi = std::min(a[i].end_m, b[j].end_m);
    if (hi > lo) out.push_back({lo, hi});
    // drop whichever ends first: it cannot meet anything further up in the other list
    if (a[i].end_m < b[j].end_m) {
      ++i;
    } else {
      ++j;
    }
  }
  return out;
}

RecoveryMeter::RecoveryMeter(int stripes, double width_m, double length_m)
    : stripes_(std::max(stripes, 0)),
      width_m_(width_m > 0.0 ? width_m : 0.0),
      stripe_length_m_(stripes_ > 0 && length_m > 0.0 ? length_m / stripes_ : 0.0),
      station_(stripes_),
      lost_(stripes_) {}

RecoveryMeter::Holder& RecoveryMeter::holder(int agent) {
  auto [it, added] = agents_.try_emplace(agent);
  if (added) it->second.apd = AreaParts(stripes_);
  return it->second;
}

std::vector<Interval> RecoveryMeter::held(int stripe) const {
  std::vector<Interval> all = station_.stripe(stripe);
  for (const auto& [id, h] : agents_) {
    if (h.failed) continue;
    const auto& s = h.apd.stripe(stripe);
    all.insert(all.end(), s.begin(), s.end());
  }
  return normalize_stripe(all);
}

double RecoveryMeter::lose(const AreaParts& apd) {
  double lost_now_m = 0.0;
  for (int s = 0; s < stripes_; ++s) {
    if (apd.stripe(s).empty()) continue;
    std::vector<Interval> gone = stripe_minus(apd.stripe(s), held(s));
    // slivers between pictures that abut count as covered in the scoring: not lost either
    std::erase_if(gone, [](const Interval& v) { return v.end_m - v.start_m < kCoverageSlack_m; });
    if (gone.empty()) continue;
    lost_now_m += covered_length(gone, width_m_);
    gone.insert(gone.end(), lost_.stripe(s).begin(), lost_.stripe(s).end());
    lost_.set_stripe(s, gone);
  }
  lost_m_ += lost_now_m;
  return lost_now_m;
}

void RecoveryMeter::agent_report(int agent, const AreaParts& apd) {
  if (apd.stripe_count() != stripes_) return;
  Holder& h = holder(agent);
  if (h.failed) {
    // a report written just before the failure and read after it: those pictures are lost too
    AreaParts late(stripes_);
    for (int s = 0; s < stripes_; ++s)
      late.set_stripe(s, stripe_minus(apd.stripe(s), h.apd.stripe(s)));
    h.apd = apd;
    lose(late);
    return;
  }
  for (int s = 0; s < stripes_; ++s) {
    if (lost_.stripe(s).empty()) continue;
    const std::vector<Interval> fresh = stripe_minus(apd.stripe(s), h.apd.stripe(s));
    const double gained = covered_length(fresh, width_m_);
    if (!(gained > 0.0)) continue;
    const double recovered = covered_length(stripe_and(fresh, lost_.stripe(s)), width_m_);
    distance_m_ += stripe_length_m_ * recovered / gained;
    recovered_m_ += recovered;
    lost_.set_stripe(s, stripe_minus(lost_.stripe(s), fresh));
  }
  h.apd = apd;
}

void RecoveryMeter::station_report(const AreaParts& map) {
  // Only kept for the failures to come: ground lost already stays lost until an agent photographs
  // it again. The station also receives the recovering agent's pictures, often before that agent's
  // own report is read; removing them here would hide its recovery. (What a failed agent delivered
  // in its last second and the station reports after the failure is counted lost: at most a
  // second of one agent's pictures, an overestimate of the recovery.)
  if (map.stripe_count() == stripes_) station_ = map;
}

double RecoveryMeter::agent_failed(int agent) {
  Holder& h = holder(agent);
  if (h.failed) return 0.0;
  h.failed = true;
  return fraction(lose(h.apd));
}

double RecoveryMeter::fraction(double length_m) const {
  return stripes_ > 0 && width_m_ > 0.0 ? length_m / (stripes_ * width_m_) : 0.0;
}

double RecoveryMeter::recovered_fraction() const { return fraction(recovered_m_); }

double RecoveryMeter::lost_at_failures_fraction() const { return fraction(lost_m_); }

double RecoveryMeter::lost_fraction() const { return lost_.covered_fraction(width_m_); }

}  // namespace uavsim::missions::coverage
