#include "radio/gcs_relay.hpp"

#include <arpa/inet.h>
#include <fcntl.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>

namespace uavsim::server::radio {

namespace {

constexpr size_t kMaxDatagramBytes = 65536;
constexpr size_t kMaxReadsPerPump = 1024;  // per socket: bounds the loop thread's work per step
constexpr size_t kMaxInFlight = 1u << 14;

int bind_udp(const std::string& address, uint16_t port, uint16_t* bound_port, std::string* error) {
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_port = htons(port);
  if (inet_pton(AF_INET, address.c_str(), &a.sin_addr) != 1) {
    *error = "bad bind address '" + address + "'";
    return -1;
  }
  const int fd = socket(AF_INET, SOCK_DGRAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
  if (fd < 0) {
    *error = std::string("socket: ") + std::strerror(errno);
    return -1;
  }
  if (bind(fd, reinterpret_cast<sockaddr*>(&a), sizeof(a)) != 0) {
    *error = "udp:" + address + ":" + std::to_string(port) + ": " + std::strerror(errno);
    close(fd);
    return -1;
  }
  socklen_t len = sizeof(a);
  getsockname(fd, reinterpret_cast<sockaddr*>(&a), &len);
  *bound_port = ntohs(a.sin_port);
  return fd;
}

}  // namespace

std::unique_ptr<GcsRelay> GcsRelay::open(const std::string& bind_address, uint16_t uav_port,
                                         uint16_t gcs_port,
                                         const std::optional<std::string>& gcs_host,
                                         std::optional<uint16_t> gcs_target_port, uint64_t seed,
                                         std::string* error) {
  std::unique_ptr<GcsRelay> r(new GcsRelay());
  r->rng_.seed(seed);
  if (gcs_host || gcs_target_port) {
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_port = htons(gcs_target_port.value_or(0));
    if (!gcs_target_port ||
        inet_pton(AF_INET, gcs_host.value_or("127.0.0.1").c_str(), &a.sin_addr) != 1) {
      *error = "the GCS target needs an IPv4 address and a port";
      return nullptr;
    }
    r->gcs_peer_ = a;
  }
  r->uav_fd_ = bind_udp(bind_address, uav_port, &r->uav_port_, error);
  if (r->uav_fd_ < 0) return nullptr;
  r->gcs_fd_ = bind_udp(bind_address, gcs_port, &r->gcs_port_, error);
  if (r->gcs_fd_ < 0) return nullptr;
  return r;
}

GcsRelay::~GcsRelay() {
  if (uav_fd_ >= 0) close(uav_fd_);
  if (gcs_fd_ >= 0) close(gcs_fd_);
}

double GcsRelay::uniform() {
  return static_cast<double>(rng_() >> 11) * (1.0 / 9007199254740992.0);
}

void GcsRelay::impair(double loss_probability, double latency_s, double outage_s, double now_s) {
  impairment_.loss_probability = loss_probability;
  impairment_.latency_s = latency_s;
  if (outage_s > 0.0) impairment_.outage_until_s = now_s + outage_s;
}

void GcsRelay::reset(uint64_t seed) {
  rng_.seed(seed);
  impairment_ = RelayImpairment{};
  in_flight_.clear();
  stats_ = RelayStats{};
}

void GcsRelay::receive(int fd, bool to_gcs, double now_s) {
  std::vector<uint8_t> buf(kMaxDatagramBytes);
  for (size_t k = 0; k < kMaxReadsPerPump; ++k) {
    sockaddr_in from{};
    socklen_t len = sizeof(from);
    const ssize_t n = recvfrom(fd, buf.data(), buf.size(), MSG_DONTWAIT,
                               reinterpret_cast<sockaddr*>(&from), &len);
    if (n < 0)
      return;  // EAGAIN (drained) or an ICMP error from an earlier send: nothing to read now
    // the sender of each side is where that side's traffic goes back to
    (to_gcs ? uav_peer_ : gcs_peer_) = from;
    uint64_t& dropped = to_gcs ? stats_.to_gcs_dropped : stats_.to_uav_dropped;
    // outage, then the loss draw (drawn for every datagram outside an outage, in reading order)
    if (now_s < impairment_.outage_until_s) {
      ++dropped;
      continue;
    }
    if (impairment_.loss_probability > 0.0 && uniform() < impairment_.loss_probability) {
      ++dropped;
      continue;
    }
    if (in_flight_.size() >= kMaxInFlight) {
      ++dropped;
      continue;
    }
    InFlight d;
    d.due_s = now_s + impairment_.latency_s;
    d.to_gcs = to_gcs;
    d.bytes.assign(buf.begin(), buf.begin() + n);
    // keep the list ordered by due time; equal times keep arrival order
    auto at = std::upper_bound(in_flight_.begin(), in_flight_.end(), d.due_s,
                               [](double t, const InFlight& x) { return t < x.due_s; });
    in_flight_.insert(at, std::move(d));
  }
}

void GcsRelay::pump(double now_s) {
  receive(uav_fd_, true, now_s);
  receive(gcs_fd_, false, now_s);
  size_t sent = 0;
  for (; sent < in_flight_.size() && in_flight_[sent].due_s <= now_s + 1e-9; ++sent) {
    const InFlight& d = in_flight_[sent];
    if (!carrier_) {
      forward(d.to_gcs, d.bytes);
    } else if (!carrier_(d.to_gcs, d.bytes)) {
      ++(d.to_gcs ? stats_.to_gcs_dropped : stats_.to_uav_dropped);  // the radio refused it
    }
  }
  in_flight_.erase(in_flight_.begin(), in_flight_.begin() + static_cast<std::ptrdiff_t>(sent));
}

void GcsRelay::deliver(bool to_gcs, const std::vector<uint8_t>& bytes) { forward(to_gcs, bytes); }

void GcsRelay::forward(bool to_gcs, const std::vector<uint8_t>& bytes) {
  const std::optional<sockaddr_in>& peer = to_gcs ? gcs_peer_ : uav_peer_;
  uint64_t& forwarded = to_gcs ? stats_.to_gcs_forwarded : stats_.to_uav_forwarded;
  uint64_t& dropped = to_gcs ? stats_.to_gcs_dropped : stats_.to_uav_dropped;
  // vehicle -> GCS leaves from the GCS-side socket, GCS -> vehicle from the vehicle-side one
  const int fd = to_gcs ? gcs_fd_ : uav_fd_;
  if (peer && sendto(fd, bytes.data(), bytes.size(), MSG_DONTWAIT,
                     reinterpret_cast<const sockaddr*>(&*peer), sizeof(*peer)) >= 0) {
    ++forwarded;
  } else {
    ++dropped;  // no peer yet, or a full socket buffer: a lost datagram, as on a real link
  }
}

GcsRelaySet& GcsRelaySet::create(sim::Simulation& sim, std::string bind_address) {
  return sim.own(std::make_unique<GcsRelaySet>(sim, std::move(bind_address)));
}

GcsRelaySet& GcsRelaySet::attach(sim::Simulation& sim, std::string bind_address) {
  GcsRelaySet& set = create(sim, std::move(bind_address));
  set.schedule(sim.schedule());
  return set;
}

void GcsRelaySet::schedule(sim::StepSchedule& steps) {
  // at control steps: the loop's own granularity for I/O with the outside world
  steps.add(sim::Phase::kPostControl, "gcs_relays", [this] { pump(); });
  steps.add_reset("gcs_relays", [this](uint64_t seed) { reset(seed); });
}

GcsRelaySet::GcsRelaySet(sim::Simulation& sim, std::string bind_address)
    : sim_(sim), bind_address_(std::move(bind_address)), relays_(sim.vehicle_count()) {}

GcsRelay* GcsRelaySet::open(size_t vehicle, uint16_t uav_port, uint16_t gcs_port,
                            const std::optional<std::string>& gcs_host,
                            std::optional<uint16_t> gcs_target_port, std::string* error) {
  if (vehicle >= relays_.size()) {
    *error = "no vehicle " + std::to_string(vehicle);
    return nullptr;
  }
  relays_[vehicle].reset();  // frees the ports first, so the same ones can be asked for again
  relays_[vehicle] = GcsRelay::open(bind_address_, uav_port, gcs_port, gcs_host, gcs_target_port,
                                    relay_seed(sim_.config().seed, vehicle), error);
  if (relays_[vehicle] && radio_) {
    // the new relay counts only its own datagrams' losses
    radio_->take_losses(vehicle, true);
    radio_->take_losses(vehicle, false);
    GcsRadioLink* radio = radio_.get();
    relays_[vehicle]->set_carrier([radio, vehicle](bool to_gcs, const std::vector<uint8_t>& b) {
      return radio->send(vehicle, to_gcs, b);
    });
  }
  return relays_[vehicle].get();
}

void GcsRelaySet::use_radio(std::unique_ptr<GcsRadioLink> radio) { radio_ = std::move(radio); }

GcsRelay* GcsRelaySet::relay(size_t vehicle) {
  return vehicle < relays_.size() ? relays_[vehicle].get() : nullptr;
}

void GcsRelaySet::pump() {
  const double now = sim_.time_s();
  for (auto& r : relays_) {
    if (r) r->pump(now);
  }
  if (!radio_) return;
  // over the radio: what it delivers by now goes on to its peer, what it lost counts as dropped
  std::vector<GcsRadioLink::Arrival> arrived;
  radio_->step(&arrived);
  for (const GcsRadioLink::Arrival& a : arrived) {
    if (a.vehicle < relays_.size() && relays_[a.vehicle])
      relays_[a.vehicle]->deliver(a.to_gcs, a.bytes);
  }
  for (size_t i = 0; i < relays_.size(); ++i) {
    if (relays_[i]) {
      relays_[i]->count_carrier_losses(radio_->take_losses(i, true), radio_->take_losses(i, false));
    }
  }
  const std::string why = radio_->failure();
  if (!why.empty() && !failure_reported_) {
    failure_reported_ = true;
    if (on_failure_) on_failure_(why);
  }
}

void GcsRelaySet::reset(uint64_t seed) {
  for (size_t i = 0; i < relays_.size(); ++i) {
    if (relays_[i]) relays_[i]->reset(relay_seed(seed, i));
  }
  if (radio_) radio_->reset(seed);
}

}  // namespace uavsim::server::radio
