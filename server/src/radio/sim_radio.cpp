#include "radio/sim_radio.hpp"

#include <memory>

namespace uavsim::server::radio {

SimRadio& SimRadio::create(sim::Simulation& sim, const RadioConfig& config) {
  return sim.own(std::make_unique<SimRadio>(sim, config));
}

SimRadio& SimRadio::attach(sim::Simulation& sim, const RadioConfig& config) {
  SimRadio& radio = create(sim, config);
  radio.schedule(sim.schedule());
  return radio;
}

void SimRadio::schedule(sim::StepSchedule& steps) {
  steps.add(sim::Phase::kPrePhysics, "radio", [this] { advance(); });
  steps.add_reset("radio", [this](uint64_t seed) { reset(seed); });
}

SimRadio::SimRadio(sim::Simulation& sim, const RadioConfig& config)
    : sim_(sim),
      model_(sim.vehicle_count(), config, radio_seed(sim.config().seed), sim.physics_dt_s()),
      positions_enu_m_(sim.vehicle_count(), Eigen::Vector3d::Zero()) {}

SendResult SimRadio::send(size_t from, int to, const std::vector<uint8_t>& data) {
  return model_.send(from, to, data, sim_.time_s());
}

void SimRadio::advance(bool starting_now) {
  // positions at the transmit instant, read only when a frame goes on air
  if (model_.has_due(sim_.time_s())) {
    for (size_t i = 0; i < positions_enu_m_.size(); ++i)
      positions_enu_m_[i] = sim_.truth(i).position_enu_m;
  }
  std::vector<Delivery> arrived;
  model_.step(sim_.time_s(), positions_enu_m_, &arrived, starting_now);
  for (Delivery& d : arrived) {
    // bounded: a radio nobody listens to must not grow without end
    if (inbox_.size() >= kMaxInbox) {
      ++inbox_overflows_;
      continue;
    }
    inbox_.push_back(std::move(d));
  }
}

std::vector<Delivery> SimRadio::take_deliveries() {
  std::vector<Delivery> out;
  out.swap(inbox_);
  return out;
}

void SimRadio::reset(uint64_t seed) {
  model_.reset(radio_seed(seed));
  inbox_.clear();
}

}  // namespace uavsim::server::radio
