#include "radio/gcs_radio_link.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "physics/object_bodies.hpp"
#include "radio/sim_radio.hpp"

namespace uavsim::server::radio {

RadioConfig gcs_wifi_config() {
  RadioConfig c;
  c.technology = Technology::k80211;
  c.propagation = Propagation::kLogDistance;
  c.tx_power_dbm = 20.0;
  c.sensitivity_dbm = -82.0;
  c.shadowing_sigma_db = 4.0;
  // what the ns3 backend always does (ns3_channel.hpp)
  c.collisions = true;
  c.mac_header_bytes = 11;
  return c;
}

Eigen::Vector3d default_gcs_position(const sim::Simulation& sim) {
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  for (size_t i = 0; i < sim.vehicle_count(); ++i) sum += sim.truth(i).position_enu_m;
  if (sim.vehicle_count() > 0) sum /= static_cast<double>(sim.vehicle_count());
  return sum + Eigen::Vector3d(0.0, 0.0, kGcsAntennaHeight_m);
}

std::string validate_gcs_position(const Eigen::Vector3d& p) {
  for (int k = 0; k < 3; ++k) {
    if (!(std::isfinite(p[k]) && std::abs(p[k]) <= kMaxGcsCoordinate_m)) {
      return "the GCS position needs three finite coordinates within +-100000 m";
    }
  }
  return "";
}

void apply_world_gcs_settings(const physics::World& world, bool backend_given, bool* use_ns3,
                              GcsRadioOptions* options) {
  const auto b = world_backend(world, "uavsim:gcs_link_backend");
  if (b && !backend_given) *use_ns3 = *b == Backend::kNs3;
  const std::vector<double> p = physics::custom_numeric(world, "uavsim:gcs_position");
  if (!p.empty()) {
    const Eigen::Vector3d at = p.size() == 3 ? Eigen::Vector3d(p[0], p[1], p[2])
                                             : Eigen::Vector3d::Constant(kMaxGcsCoordinate_m * 2);
    if (!validate_gcs_position(at).empty()) {
      throw physics::WorldError(
          "numeric uavsim:gcs_position needs data=\"X Y Z\": the ground station's ENU position in "
          "metres, each within +-100000");
    }
    if (!options->gcs_position_enu_m) options->gcs_position_enu_m = at;
  }
  // obstacles block the GCS link as they block the A2A radio
  BackendOptions ignored;
  apply_world_radio_settings(world, &ignored, true, &options->config);
}

namespace {

std::unique_ptr<RadioChannel> make_gcs_channel(sim::Simulation& sim,
                                               const GcsRadioOptions& options) {
  // a node per vehicle and the ground station's
  return make_channel({Backend::kNs3, options.ns3}, sim.vehicle_count() + 1, options.config,
                      GcsRadioLink::gcs_radio_seed(sim.config().seed), sim.control_dt_s());
}

Eigen::Vector3d checked_position(const sim::Simulation& sim, const GcsRadioOptions& options) {
  const Eigen::Vector3d p = options.gcs_position_enu_m.value_or(default_gcs_position(sim));
  const std::string why = validate_gcs_position(p);
  if (!why.empty()) throw std::invalid_argument(why);
  return p;
}

}  // namespace

GcsRadioLink::GcsRadioLink(sim::Simulation& sim, const GcsRadioOptions& options)
    : GcsRadioLink(sim, nullptr, checked_position(sim, options)) {
  if (options.config.technology != Technology::k80211) {
    throw std::invalid_argument("the GCS link's radio is 802.11");
  }
  channel_ = make_gcs_channel(sim, options);
  channel_->set_link_loss([this](size_t from, size_t to) { return link_loss_db(from, to); });
}

GcsRadioLink::GcsRadioLink(sim::Simulation& sim, std::unique_ptr<RadioChannel> channel,
                           const Eigen::Vector3d& gcs_position_enu_m)
    : sim_(sim),
      channel_(std::move(channel)),
      gcs_enu_m_(gcs_position_enu_m),
      ground_(sim.vehicle_count()),
      sights_(sim.world(), ground_ + 1),
      positions_enu_m_(ground_ + 1, gcs_position_enu_m),
      velocities_enu_m_s_(ground_ + 1, Eigen::Vector3d::Zero()),
      reported_losses_(2 * ground_, 0) {
  if (channel_) {
    if (channel_->vehicle_count() != ground_ + 1) {
      throw std::invalid_argument("the GCS link's channel needs one node per vehicle and one more");
    }
    channel_->set_link_loss([this](size_t from, size_t to) { return link_loss_db(from, to); });
  }
}

double GcsRadioLink::link_loss_db(size_t from, size_t to) {
  return sights_.loss_db(from, to, positions_enu_m_[from], positions_enu_m_[to],
                         channel_->config().obstacle_loss_db, sim_.time_s());
}

bool GcsRadioLink::send(size_t vehicle, bool to_gcs, const std::vector<uint8_t>& bytes) {
  if (vehicle >= ground_) return false;
  const size_t from = to_gcs ? vehicle : ground_;
  const size_t to = to_gcs ? ground_ : vehicle;
  return channel_->send(from, static_cast<int>(to), bytes, sim_.time_s()).seq.has_value();
}

void GcsRadioLink::step(std::vector<Arrival>* out) {
  // the vehicles' true positions (and velocities) when the channel needs them; the ground node
  // stays where it stands
  if (channel_->has_due(sim_.time_s())) {
    for (size_t i = 0; i < ground_; ++i) {
      const fc::TruthState t = sim_.truth(i);
      positions_enu_m_[i] = t.position_enu_m;
      velocities_enu_m_s_[i] = t.velocity_enu_m_s;
    }
    channel_->set_velocities(velocities_enu_m_s_);
  }
  std::vector<Delivery> arrived;
  channel_->step(sim_.time_s(), positions_enu_m_, &arrived);
  for (Delivery& d : arrived) {
    // only links to or from the ground node carry datagrams
    const bool to_gcs = d.to == ground_;
    if (to_gcs == (d.from == ground_)) continue;
    out->push_back({to_gcs ? d.from : d.to, to_gcs, d.queued_s, d.time_s, std::move(d.data)});
  }
}

uint64_t GcsRadioLink::channel_losses(size_t vehicle, bool to_gcs) const {
  // every frame that went on air ends delivered or in exactly one of these (radio_channel.hpp)
  const LinkStats& s = to_gcs ? channel_->link(vehicle, ground_) : channel_->link(ground_, vehicle);
  return s.lost + s.collided + s.out_of_range;
}

uint64_t GcsRadioLink::take_losses(size_t vehicle, bool to_gcs) {
  if (vehicle >= ground_) return 0;
  uint64_t& reported = reported_losses_[vehicle * 2 + (to_gcs ? 1 : 0)];
  const uint64_t now = channel_losses(vehicle, to_gcs);
  const uint64_t fresh = now - reported;
  reported = now;
  return fresh;
}

void GcsRadioLink::reset(uint64_t sim_seed) {
  channel_->reset(gcs_radio_seed(sim_seed));
  std::fill(reported_losses_.begin(), reported_losses_.end(), 0);
  sights_.clear();
}

}  // namespace uavsim::server::radio
