// The loop thread's side of the MAVLink endpoints: the inbox hand-off to the flight controllers,
// the telemetry wake-ups and flushes (endpoint_core.hpp), and MavlinkServer's methods.
#include "mavlink/endpoint.hpp"

#include <chrono>
#include <mutex>

#include "mavlink/endpoint_core.hpp"

namespace uavsim::server::mavlink {

void MavlinkServer::Core::wake() {
  wakeups.fetch_add(1, std::memory_order_relaxed);
  waker->wake();  // one eventfd write until the I/O thread has served it
}

bool MavlinkServer::Core::flush_queued(double timeout_s) {
  std::uint64_t generation = 0;
  {
    std::lock_guard lock(flush_mutex);
    generation = ++flush_requested;
  }
  wake();
  using SteadyClock = std::chrono::steady_clock;
  const auto deadline = SteadyClock::now() + std::chrono::duration_cast<SteadyClock::duration>(
                                                 std::chrono::duration<double>(timeout_s));
  std::unique_lock lock(flush_mutex);
  return flush_cv.wait_until(lock, deadline, [&] {
    return flush_done >= generation || stop.load();
  }) && flush_done >= generation;
}

void MavlinkServer::Core::publish_flushed(std::uint64_t generation) {
  {
    std::lock_guard lock(flush_mutex);
    if (generation <= flush_done) return;
    flush_done = generation;
  }
  flush_cv.notify_all();
}

void MavlinkServer::Core::push_event(std::size_t vehicle, InEvent&& ev) {
  Vehicle& v = *vehicles[vehicle];
  bool post = false;
  {
    std::lock_guard lock(v.inbox_mutex);
    if (ev.kind == InEvent::Kind::kFrame) {
      if (v.inbox_frames >= config.inbox_frames) {
        StatCounters::add(v.stats.inbox_dropped);
        return;
      }
      ++v.inbox_frames;
    }
    v.inbox.push_back(std::move(ev));
    if (!v.task_posted) v.task_posted = post = true;
  }
  if (post) {
    std::weak_ptr<Core> weak = self;
    sim.post(vehicle, [weak, vehicle](fc::FlightController& fc) {
      if (auto core = weak.lock()) core->drain_inbox(vehicle, fc);
    });
  }
}

void MavlinkServer::Core::after_reset() {
  for (std::size_t vehicle = 0; vehicle < vehicles.size(); ++vehicle) {
    Vehicle& v = *vehicles[vehicle];
    bool post = false;
    {
      std::lock_guard lock(v.inbox_mutex);
      post = !v.inbox.empty();
      v.task_posted = post;
    }
    if (!post) continue;
    std::weak_ptr<Core> weak = self;
    sim.post(vehicle, [weak, vehicle](fc::FlightController& fc) {
      if (auto core = weak.lock()) core->drain_inbox(vehicle, fc);
    });
  }
}

void MavlinkServer::Core::drain_inbox(std::size_t vehicle, fc::FlightController& fc) {
  Vehicle& v = *vehicles[vehicle];
  std::vector<InEvent> events;
  {
    std::lock_guard lock(v.inbox_mutex);
    events.swap(v.inbox);
    v.inbox_frames = 0;
    v.task_posted = false;
  }
  for (InEvent& e : events) {
    switch (e.kind) {
      case InEvent::Kind::kConnect:
        v.link->on_connect(e.client, std::move(e.outbox));
        if (config.on_client) config.on_client(vehicle, true, e.peer);
        break;
      case InEvent::Kind::kDisconnect:
        v.link->on_disconnect(e.client);
        if (config.on_client) config.on_client(vehicle, false, e.peer);
        break;
      case InEvent::Kind::kFrame:
        if (!e.raw.empty()) v.link->log_received(e.raw);
        v.link->on_frame(e.client, e.frame, fc);
        break;
    }
  }
  (void)v.link->take_queued();  // the replies go with this wake-up
  wake();
}

void MavlinkServer::Core::on_control_step() {
  bool any = false;
  for (auto& v : vehicles) {
    v->link->on_control_step();
    any = v->link->take_queued() || any;
  }
  if (any) wake();
}

MavlinkServer::MavlinkServer(sim::Simulation& sim, const EndpointConfig& config,
                             net::EventLoop* io_loop)
    : core_(std::make_shared<Core>(sim, config, io_loop)) {
  core_->open(core_);
  // sim_vehicle.py --auto-sysid: vehicle i is system i + 1
  if (config.auto_sysid) {
    for (std::size_t i = 0; i < sim.vehicle_count(); ++i) {
      sim.post(i, [i](fc::FlightController& fc) {
        fc.set_param("SYSID_THISMAV", static_cast<double>(i + 1));
      });
    }
  }
}

MavlinkServer::~MavlinkServer() { core_->shutdown(); }

void MavlinkServer::schedule(sim::StepSchedule& steps) {
  std::weak_ptr<Core> weak = core_;
  steps.add(sim::Phase::kPostControl, "mavlink", [weak] {
    if (auto core = weak.lock()) core->on_control_step();
  });
  steps.add_reset("mavlink", [weak](uint64_t) {
    if (auto core = weak.lock()) core->after_reset();
  });
}

std::size_t MavlinkServer::vehicle_count() const { return core_->vehicles.size(); }
std::uint16_t MavlinkServer::port(std::size_t vehicle) const {
  return core_->vehicles.at(vehicle)->port;
}
std::uint16_t MavlinkServer::udp_port(std::size_t vehicle, std::size_t k) const {
  return core_->vehicles.at(vehicle)->udp_ports.at(k);
}
EndpointStats MavlinkServer::stats(std::size_t vehicle) const {
  const Core::Vehicle& v = *core_->vehicles.at(vehicle);
  EndpointStats s = v.stats.snapshot();
  if (v.acceptor) s.fd_exhausted_accepts = v.acceptor->exhausted_accepts();
  return s;
}
std::size_t MavlinkServer::client_count(std::size_t vehicle) const {
  return static_cast<std::size_t>(core_->vehicles.at(vehicle)->stats.clients_now.load());
}
const GimbalState& MavlinkServer::gimbal(std::size_t vehicle) const {
  return core_->vehicles.at(vehicle)->link->gimbal();
}
const EndpointConfig& MavlinkServer::config() const { return core_->config; }

bool MavlinkServer::set_link_down(std::size_t vehicle, bool down) {
  if (vehicle >= core_->vehicles.size()) return false;
  core_->vehicles[vehicle]->link_down.store(down);
  core_->wake();
  return true;
}

bool MavlinkServer::link_down(std::size_t vehicle) const {
  return vehicle < core_->vehicles.size() && core_->vehicles[vehicle]->link_down.load();
}

bool MavlinkServer::flush_queued(double timeout_s) { return core_->flush_queued(timeout_s); }

std::uint64_t MavlinkServer::io_wakeups() const {
  return core_->wakeups.load(std::memory_order_relaxed);
}

void MavlinkServer::set_seq_listener(std::function<void()> listener) {
  std::lock_guard lock(core_->seq_listener_mutex);
  core_->seq_listener = std::move(listener);
}

bool MavlinkServer::seq_processed(std::size_t vehicle, std::uint8_t seq) const {
  if (vehicle >= core_->vehicles.size()) return false;
  const Core::Vehicle& v = *core_->vehicles[vehicle];
  std::lock_guard lock(v.seq_mutex);
  for (const auto& [client, last] : v.last_seq) {
    if (static_cast<std::uint8_t>(last - seq) < 128) return true;
  }
  return false;
}

}  // namespace uavsim::server::mavlink
