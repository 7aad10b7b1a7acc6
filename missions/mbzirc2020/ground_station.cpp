#include "ground_station.hpp"

#include <algorithm>
#include <cstdio>

#include "vehicle_fsm.hpp"

namespace uavsim::missions::mbzirc2020 {
namespace {

double point_segment_distance(const Eigen::Vector2d& p, const Eigen::Vector2d& a,
                              const Eigen::Vector2d& b) {
  const Eigen::Vector2d ab = b - a;
  const double len2 = ab.squaredNorm();
  const double t = len2 > 0 ? std::clamp((p - a).dot(ab) / len2, 0.0, 1.0) : 0.0;
  return (a + t * ab - p).norm();
}

double cross(const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  return a.x() * b.y() - a.y() * b.x();
}

std::string area_text(const AirspaceArea& a) {
  char buf[96];
  std::snprintf(buf, sizeof(buf), "(%.1f, %.1f) -> (%.1f, %.1f)", a.from_enu_m.x(),
                a.from_enu_m.y(), a.to_enu_m.x(), a.to_enu_m.y());
  return buf;
}

}  // namespace

double segment_distance(const Eigen::Vector2d& a0, const Eigen::Vector2d& a1,
                        const Eigen::Vector2d& b0, const Eigen::Vector2d& b1) {
  // crossing segments are 0 apart; otherwise the closest pair involves an endpoint
  const double d1 = cross(a1 - a0, b0 - a0), d2 = cross(a1 - a0, b1 - a0);
  const double d3 = cross(b1 - b0, a0 - b0), d4 = cross(b1 - b0, a1 - b0);
  if (((d1 > 0) != (d2 > 0)) && ((d3 > 0) != (d4 > 0)) && d1 != 0 && d2 != 0 && d3 != 0 && d4 != 0)
    return 0.0;
  return std::min({point_segment_distance(a0, b0, b1), point_segment_distance(a1, b0, b1),
                   point_segment_distance(b0, a0, a1), point_segment_distance(b1, a0, a1)});
}

GroundStation::GroundStation(const GroundStationConfig& config, int uav_count)
    : config_(config), uavs_(static_cast<size_t>(uav_count)) {}

void GroundStation::on_status(int uav, const UavStatus& s, double now_s) {
  Uav& u = uavs_[static_cast<size_t>(uav)];
  u.heard = true;
  u.status = s;
  u.last_status_s = now_s;
  if (first_heard_s_ < 0) first_heard_s_ = now_s;
}

void GroundStation::on_airspace(int uav, const std::optional<AirspaceArea>& a, double now_s) {
  Uav& u = uavs_[static_cast<size_t>(uav)];
  if (!a) {
    // release: echo the NaN so the UAV sees its release acknowledged too
    if (u.granted || u.pending)
      queued_notes_.push_back("uav" + std::to_string(uav) + " airspace released");
    u.granted.reset();
    u.pending.reset();
    queued_.push_back({uav, kTopicAirspace, encode_airspace(std::nullopt)});
    return;
  }
  u.granted.reset();  // a new request replaces what the UAV held
  u.pending = a;
  u.pending_since_s = now_s;
}

void GroundStation::on_popped(int uav, const Eigen::Vector2d& p, double) {
  for (const Eigen::Vector2d& q : popped_) {
    if ((q - p).norm() < config_.popped_merge_m) return;
  }
  popped_.push_back(p);
  char buf[128];
  std::snprintf(buf, sizeof(buf), "uav%d reports a balloon popped at (%.1f, %.1f): %zu/%d", uav,
                p.x(), p.y(), popped_.size(), config_.balloon_count);
  queued_notes_.push_back(buf);
}

bool GroundStation::conflicts(int uav, const AirspaceArea& a) const {
  for (size_t j = 0; j < uavs_.size(); ++j) {
    if (static_cast<int>(j) == uav || uavs_[j].out) continue;
    const Uav& o = uavs_[j];
    if (o.granted && segment_distance(a.from_enu_m, a.to_enu_m, o.granted->from_enu_m,
                                      o.granted->to_enu_m) < config_.min_separation_m) {
      return true;
    }
    const bool flying = o.heard && !o.status.landed && !o.status.ready && !o.status.failed;
    if (flying) {
      const Eigen::Vector2d q = o.status.position_enu_m.head<2>();
      if (segment_distance(a.from_enu_m, a.to_enu_m, q, q) < config_.min_separation_m) return true;
    }
  }
  return false;
}

std::vector<GcsOutgoing> GroundStation::step(double now_s, std::vector<std::string>* notes) {
  std::vector<GcsOutgoing> out = std::move(queued_);
  queued_.clear();
  if (notes) notes->insert(notes->end(), queued_notes_.begin(), queued_notes_.end());
  queued_notes_.clear();
  auto note = [&](const std::string& s) {
    if (notes) notes->push_back(s);
  };
  const int n = static_cast<int>(uavs_.size());

  // start (seed: the GUI "start[s] ... all the UAVs at the same time"): once every UAV is ready
  if (!started_) {
    int ready = 0;
    for (const Uav& u : uavs_) ready += u.heard && u.status.ready ? 1 : 0;
    const bool timeout = first_heard_s_ >= 0 && now_s - first_heard_s_ > config_.start_timeout_s;
    if (ready == n || (timeout && ready > 0)) {
      started_ = true;
      for (int i = 0; i < n; ++i) {
        Uav& u = uavs_[static_cast<size_t>(i)];
        if (u.heard && u.status.ready) {
          out.push_back({i, kTopicState, encode_command(GcsCommand::kStart)});
          u.last_status_s = now_s;
        } else {
          u.out = true;
        }
      }
      note("start: " + std::to_string(ready) + "/" + std::to_string(n) + " UAVs ready");
    }
    return out;
  }

  // a UAV that reports a failure or falls silent is out: the others take its side over
  for (int i = 0; i < n; ++i) {
    Uav& u = uavs_[static_cast<size_t>(i)];
    if (u.out || u.status.landed) continue;
    if (u.status.failed || now_s - u.last_status_s > config_.stale_s) {
      u.out = true;
      u.granted.reset();
      u.pending.reset();
      note("uav" + std::to_string(i) + (u.status.failed ? " failed" : " silent") +
           ": out of the mission");
      for (int j = 0; j < n; ++j) {
        Uav& o = uavs_[static_cast<size_t>(j)];
        if (j == i || o.out || o.take_over_sent || o.status.landed) continue;
        o.take_over_sent = true;
        out.push_back({j, kTopicState, encode_command(GcsCommand::kTakeOver)});
        note("uav" + std::to_string(j) + " takes over the side of uav" + std::to_string(i));
      }
    }
  }

  // a UAV that has done its own side's scans while balloons remain (in 6 of 15 two-UAV seeds one
  // UAV popped four while the other had landed) goes on to the other half; its pierces there are
  // granted below like any other, apart from the UAV still at work on that side
  if (static_cast<int>(popped_.size()) < config_.balloon_count) {
    for (int i = 0; i < n; ++i) {
      Uav& u = uavs_[static_cast<size_t>(i)];
      if (u.out || u.retask_sent || u.status.landed ||
          u.status.state != static_cast<uint8_t>(VehicleState::kScansDone)) {
        continue;
      }
      u.retask_sent = true;
      out.push_back({i, kTopicState, encode_command(GcsCommand::kReTask)});
      note("uav" + std::to_string(i) + " has done its scans, " + std::to_string(popped_.size()) +
           "/" + std::to_string(config_.balloon_count) +
           " balloons reported: re-tasked to the other half");
    }
  }

  // grant pending requests, oldest first
  std::vector<int> order;
  for (int i = 0; i < n; ++i) {
    if (uavs_[static_cast<size_t>(i)].pending) order.push_back(i);
  }
  std::sort(order.begin(), order.end(), [&](int a, int b) {
    return uavs_[static_cast<size_t>(a)].pending_since_s <
           uavs_[static_cast<size_t>(b)].pending_since_s;
  });
  for (int i : order) {
    Uav& u = uavs_[static_cast<size_t>(i)];
    if (conflicts(i, *u.pending)) continue;
    u.granted = u.pending;
    u.pending.reset();
    out.push_back({i, kTopicAirspace, encode_airspace(u.granted)});
    note("uav" + std::to_string(i) + " airspace granted " + area_text(*u.granted));
  }

  // all five reported: land everyone
  if (!land_sent_ && static_cast<int>(popped_.size()) >= config_.balloon_count) {
    land_sent_ = true;
    for (int i = 0; i < n; ++i) {
      if (!uavs_[static_cast<size_t>(i)].out)
        out.push_back({i, kTopicState, encode_command(GcsCommand::kLand)});
    }
    note("all " + std::to_string(config_.balloon_count) + " balloons reported popped: land all");
  }
  return out;
}

bool GroundStation::finished() const {
  if (!started_) return false;
  for (const Uav& u : uavs_) {
    if (!u.out && !u.status.landed) return false;
  }
  return true;
}

}  // namespace uavsim::missions::mbzirc2020
