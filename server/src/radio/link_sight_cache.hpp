// The obstacle losses of radio links (physics/line_of_sight.hpp), cached per pair of nodes: the A2A
// radio's (sim_radio.hpp) and the GCS link's (gcs_radio_link.hpp). A pair is cast again only when
// one of its ends has moved more than kMove_m since the last cast, the cast is older than kMaxAge_s
// (obstacles move too: a truck, a wall) or the losses per geom group changed. One cast serves both
// directions: the path is the same segment.
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstddef>
#include <vector>

#include "physics/line_of_sight.hpp"

namespace uavsim::server::radio {

class LinkSightCache {
 public:
  // a link's line of sight is cast again when an end moved more than this since the last cast
  static constexpr double kMove_m = 0.05;
  // ... or when the cast is older than this (a truck at 10 m/s moves 1 m)
  static constexpr double kMaxAge_s = 0.1;

  // nodes: vehicles first (world.vehicles() order), then any nodes that are no vehicle.
  LinkSightCache(const physics::World& world, size_t nodes);

  // The loss of the path between nodes from (at p_from) and to (at p_to) at sim time now_s, dB:
  // the largest loss_db[g] of the geom groups it crosses. Loop thread only (the world's data).
  double loss_db(size_t from, size_t to, const Eigen::Vector3d& p_from, const Eigen::Vector3d& p_to,
                 const std::array<double, physics::kGeomGroupCount>& loss_db, double now_s);
  // Forgets every cast (a reset). Loop thread only.
  void clear();

 private:
  struct Sight {
    bool valid = false;
    Eigen::Vector3d a_enu_m = Eigen::Vector3d::Zero();
    Eigen::Vector3d b_enu_m = Eigen::Vector3d::Zero();
    std::array<double, physics::kGeomGroupCount> loss_config_db{};
    double loss_db = 0.0;
    double cast_s = 0.0;
  };
  physics::LineOfSight sight_;
  size_t nodes_;
  std::vector<Sight> sights_;  // min(from, to) * nodes + max(from, to)
};

}  // namespace uavsim::server::radio
