#include "radio/link_sight_cache.hpp"

#include <algorithm>

namespace uavsim::server::radio {

LinkSightCache::LinkSightCache(const physics::World& world, size_t nodes)
    : sight_(world), nodes_(nodes), sights_(nodes * nodes) {}

double LinkSightCache::loss_db(size_t from, size_t to, const Eigen::Vector3d& p_from,
                               const Eigen::Vector3d& p_to,
                               const std::array<double, physics::kGeomGroupCount>& loss_db,
                               double now_s) {
  if (std::all_of(loss_db.begin(), loss_db.end(), [](double db) { return db <= 0.0; })) return 0.0;
  // one cast serves both directions, kept with its ends in (lower, higher) node order
  const bool swapped = from > to;
  const size_t a = swapped ? to : from;
  const size_t b = swapped ? from : to;
  const Eigen::Vector3d& pa = swapped ? p_to : p_from;
  const Eigen::Vector3d& pb = swapped ? p_from : p_to;
  Sight& s = sights_[a * nodes_ + b];
  if (!s.valid || s.loss_config_db != loss_db || (s.a_enu_m - pa).norm() > kMove_m ||
      (s.b_enu_m - pb).norm() > kMove_m || now_s - s.cast_s > kMaxAge_s) {
    s.loss_db = sight_.blocked_loss_db(pa, pb, a, b, loss_db);
    s.a_enu_m = pa;
    s.b_enu_m = pb;
    s.loss_config_db = loss_db;
    s.cast_s = now_s;
    s.valid = true;
  }
  return s.loss_db;
}

void LinkSightCache::clear() {
  for (Sight& s : sights_) s.valid = false;
}

}  // namespace uavsim::server::radio
