#include "radio/sim_radio.hpp"

#include <memory>
#include <sstream>
#include <stdexcept>

#include "physics/object_bodies.hpp"

namespace uavsim::server::radio {

const char* backend_name(Backend b) { return b == Backend::kNs3 ? "ns3" : "simple"; }

std::optional<Backend> backend_from_name(const std::string& name) {
  if (name == "simple") return Backend::kSimple;
  if (name == "ns3") return Backend::kNs3;
  return std::nullopt;
}

std::optional<Backend> world_backend(const physics::World& world, const std::string& key) {
  std::optional<Backend> chosen;
  for (const auto& [name, data] : physics::custom_texts(world, key)) {
    if (name != key) continue;
    chosen = backend_from_name(data);
    if (!chosen) {
      throw physics::WorldError("text " + key + " needs data=\"simple\" or \"ns3\", got \"" + data +
                                "\"");
    }
  }
  return chosen;
}

void apply_world_radio_settings(const physics::World& world, BackendOptions* backend,
                                bool backend_given, RadioConfig* config) {
  const auto b = world_backend(world, "uavsim:radio_backend");
  if (b && !backend_given) backend->backend = *b;
  const std::vector<double> loss = physics::custom_numeric(world, "uavsim:radio_obstacle_loss_db");
  if (loss.empty()) return;
  bool ok = loss.size() <= kGeomGroups;
  for (double db : loss) ok = ok && db >= 0.0 && db <= 1000.0;
  if (!ok) {
    throw physics::WorldError(
        "numeric uavsim:radio_obstacle_loss_db needs data=\"G0 [G1 ... G5]\": the loss in dB (0 to "
        "1000) a path crossing a geom of MuJoCo geom group 0, 1, ... takes");
  }
  config->obstacle_loss_db.fill(0.0);
  for (size_t g = 0; g < loss.size(); ++g) config->obstacle_loss_db[g] = loss[g];
}

std::unique_ptr<RadioChannel> make_channel(const BackendOptions& backend, size_t nodes,
                                           const RadioConfig& config, uint64_t seed,
                                           double step_s) {
  if (backend.backend == Backend::kSimple) {
    return std::make_unique<RadioModel>(nodes, config, seed, step_s);
  }
  Ns3Options o = backend.ns3;
  if (o.helper_path.empty()) o.helper_path = find_ns3_helper().value_or("");
  return std::make_unique<Ns3Channel>(nodes, config, seed, step_s, o);
}

SimRadio& SimRadio::create(sim::Simulation& sim, const RadioConfig& config,
                           const BackendOptions& backend) {
  return sim.own(std::make_unique<SimRadio>(
      sim, make_channel(backend, sim.vehicle_count(), config, radio_seed(sim.config().seed),
                        sim.physics_dt_s())));
}

SimRadio& SimRadio::attach(sim::Simulation& sim, const RadioConfig& config,
                           const BackendOptions& backend) {
  SimRadio& radio = create(sim, config, backend);
  radio.schedule(sim.schedule());
  return radio;
}

void SimRadio::schedule(sim::StepSchedule& steps) {
  // on the schedule the channel is stepped at every physics step, last in kPrePhysics (the API
  // gate's call at a control step comes before it): the grid set_pipelined asks for
  channel_->set_pipelined(true);
  steps.add(sim::Phase::kPrePhysics, "radio", [this] { advance(); });
  steps.add_reset("radio", [this](uint64_t seed) { reset(seed); });
}

SimRadio::SimRadio(sim::Simulation& sim, std::unique_ptr<RadioChannel> channel)
    : sim_(sim),
      channel_(std::move(channel)),
      sights_(sim.world(), sim.vehicle_count()),
      positions_enu_m_(sim.vehicle_count(), Eigen::Vector3d::Zero()),
      velocities_enu_m_s_(sim.vehicle_count(), Eigen::Vector3d::Zero()),
      refused_(sim.vehicle_count(), 0) {
  channel_->set_link_loss([this](size_t from, size_t to) { return link_loss_db(from, to); });
}

double SimRadio::link_loss_db(size_t from, size_t to) {
  return sights_.loss_db(from, to, positions_enu_m_[from], positions_enu_m_[to],
                         channel_->config().obstacle_loss_db, sim_.time_s());
}

SendResult SimRadio::send(size_t from, int to, const std::vector<uint8_t>& data) {
  SendResult r = channel_->send(from, to, data, sim_.time_s());
  if (!r.seq && r.error == Error::kQueueFull && from < refused_.size()) ++refused_[from];
  return r;
}

void SimRadio::advance(bool starting_now) {
  // positions (and velocities) at the transmit instant, read only when the channel needs them
  if (channel_->has_due(sim_.time_s())) {
    for (size_t i = 0; i < positions_enu_m_.size(); ++i) {
      const fc::TruthState t = sim_.truth(i);
      positions_enu_m_[i] = t.position_enu_m;
      velocities_enu_m_s_[i] = t.velocity_enu_m_s;
    }
    channel_->set_velocities(velocities_enu_m_s_);
  }
  std::vector<Delivery> arrived;
  channel_->step(sim_.time_s(), positions_enu_m_, &arrived, starting_now);
  for (Delivery& d : arrived) {
    // bounded: a radio nobody listens to must not grow without end
    if (inbox_.size() >= kMaxInbox) {
      ++inbox_overflows_;
      continue;
    }
    inbox_.push_back(std::move(d));
  }
  check_failure();
}

void SimRadio::check_failure() {
  if (failure_reported_) return;
  const std::string why = channel_->failure();
  if (why.empty()) return;
  failure_reported_ = true;
  if (on_failure_) on_failure_(why);
}

std::vector<Delivery> SimRadio::take_deliveries() {
  std::vector<Delivery> out;
  out.swap(inbox_);
  return out;
}

void SimRadio::reset(uint64_t seed) {
  channel_->reset(radio_seed(seed));
  inbox_.clear();
  refused_.assign(refused_.size(), 0);
  sights_.clear();
  check_failure();
}

}  // namespace uavsim::server::radio
