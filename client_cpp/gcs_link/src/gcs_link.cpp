// The UDP adapter of the GCS link: a non-blocking socket around a GcsLinkCore.
#include "uavsim/client/gcs_link.hpp"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

namespace uavsim::client {

namespace {
constexpr size_t kMaxDatagramBytes = 65536;
constexpr size_t kMaxReadsPerService = 256;  // bounds one call's work under a flood
}  // namespace

struct GcsLink::Impl {
  explicit Impl(const GcsLinkConfig& config) : core(config) {}
  ~Impl() {
    if (fd >= 0) close(fd);
  }
  GcsLinkCore core;
  int fd = -1;
  uint16_t local_port = 0;
  std::optional<sockaddr_in> remote;
  std::vector<uint8_t> buf = std::vector<uint8_t>(kMaxDatagramBytes);
};

std::unique_ptr<GcsLink> GcsLink::open(const GcsLinkConfig& config, const GcsLinkEndpoint& endpoint,
                                       std::string* error) {
  auto impl = std::make_unique<Impl>(config);
  sockaddr_in local{};
  local.sin_family = AF_INET;
  local.sin_port = htons(endpoint.bind_port);
  if (inet_pton(AF_INET, endpoint.bind_address.c_str(), &local.sin_addr) != 1) {
    *error = "gcs link: bad bind address '" + endpoint.bind_address + "'";
    return nullptr;
  }
  if (endpoint.remote_port != 0) {
    sockaddr_in remote{};
    remote.sin_family = AF_INET;
    remote.sin_port = htons(endpoint.remote_port);
    if (inet_pton(AF_INET, endpoint.remote_host.c_str(), &remote.sin_addr) != 1) {
      *error = "gcs link: bad remote address '" + endpoint.remote_host + "'";
      return nullptr;
    }
    impl->remote = remote;
  }
  impl->fd = socket(AF_INET, SOCK_DGRAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
  if (impl->fd < 0) {
    *error = std::string("gcs link: socket: ") + std::strerror(errno);
    return nullptr;
  }
  if (bind(impl->fd, reinterpret_cast<sockaddr*>(&local), sizeof(local)) != 0) {
    *error = "gcs link: udp:" + endpoint.bind_address + ":" + std::to_string(endpoint.bind_port) +
             ": " + std::strerror(errno);
    return nullptr;
  }
  socklen_t len = sizeof(local);
  getsockname(impl->fd, reinterpret_cast<sockaddr*>(&local), &len);
  impl->local_port = ntohs(local.sin_port);
  return std::unique_ptr<GcsLink>(new GcsLink(std::move(impl)));
}

GcsLink::GcsLink(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
GcsLink::~GcsLink() = default;

int GcsLink::fd() const { return impl_->fd; }
uint16_t GcsLink::local_port() const { return impl_->local_port; }

GcsLinkStatus GcsLink::publish(uint16_t topic, const std::vector<uint8_t>& payload) {
  return impl_->core.publish(topic, payload);
}

GcsLinkStatus GcsLink::service(int64_t now_us) {
  Impl& s = *impl_;
  // everything waiting, without blocking; malformed packets are counted by the core and ignored
  for (size_t k = 0; k < kMaxReadsPerService; ++k) {
    sockaddr_in from{};
    socklen_t len = sizeof(from);
    const ssize_t n = recvfrom(s.fd, s.buf.data(), s.buf.size(), MSG_DONTWAIT,
                               reinterpret_cast<sockaddr*>(&from), &len);
    if (n < 0) break;  // EAGAIN, or an ICMP error from an earlier send: nothing more now
    if (s.core.on_packet(s.buf.data(), static_cast<size_t>(n), now_us) == GcsLinkStatus::kOk &&
        !s.remote) {
      s.remote = from;  // a ground station answers whoever called it
    }
  }
  std::optional<std::vector<uint8_t>> packet = s.core.poll(now_us);
  if (!packet || !s.remote) return GcsLinkStatus::kOk;
  if (sendto(s.fd, packet->data(), packet->size(), MSG_DONTWAIT,
             reinterpret_cast<const sockaddr*>(&*s.remote), sizeof(*s.remote)) < 0) {
    return GcsLinkStatus::kIo;
  }
  return GcsLinkStatus::kOk;
}

int64_t GcsLink::next_service_us() const { return impl_->core.next_poll_us(); }
std::vector<GcsMessage> GcsLink::take_received() { return impl_->core.take_received(); }
GcsLinkCore& GcsLink::core() { return impl_->core; }
const GcsLinkCore& GcsLink::core() const { return impl_->core; }

std::vector<std::unique_ptr<GcsLink>> open_station_links(int count, const GcsLinkConfig& config,
                                                         std::string* error) {
  std::vector<std::unique_ptr<GcsLink>> links;
  for (int i = 0; i < count; ++i) {
    auto l = GcsLink::open(config, {"127.0.0.1", 0, "127.0.0.1", 0}, error);
    if (!l) return {};
    links.push_back(std::move(l));
  }
  return links;
}

}  // namespace uavsim::client
