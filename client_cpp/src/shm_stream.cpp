#include "shm_stream.hpp"

#include <arpa/inet.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <sys/mman.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstring>
#include <thread>

namespace uavsim::client {

namespace {

namespace shm = common::shm;
using R = Result<std::unique_ptr<ShmStream>>;

constexpr std::size_t kTokenChars = 32;  // 128 bits in hex

bool is_token(const std::string& t) {
  if (t.size() != kTokenChars) return false;
  for (char c : t) {
    if (!((c >= '0' && c <= '9') || (c >= 'a' && c <= 'f'))) return false;
  }
  return true;
}

// Opens one of the stream's FIFOs with flags, checks it is a FIFO of this user's, and unlinks its
// name (opened: no one else should find it). -1 with *error otherwise.
int open_own_fifo(const std::string& path, int flags, std::string* error) {
  const int fd = ::open(path.c_str(), flags | O_NONBLOCK | O_CLOEXEC);
  struct stat st {};
  const bool ok = fd >= 0 && fstat(fd, &st) == 0 && S_ISFIFO(st.st_mode) && st.st_uid == geteuid();
  if (!ok) *error = "shared-memory stream: " + path + ": " + (fd < 0 ? std::strerror(errno) : "not this user's FIFO");
  unlink(path.c_str());
  if (!ok && fd >= 0) close(fd);
  return ok ? fd : -1;
}

}  // namespace

R ShmStream::open(const nlohmann::json& offer) {
  // the offer's fields, each in range, before anything is opened or mapped
  const auto token = offer.find("token");
  const auto bytes = offer.find("ring_bytes");
  const auto version = offer.find("version");
  if (token == offer.end() || !token->is_string() || !is_token(token->get<std::string>())) {
    return R::fail(Error::kProtocol,
                   "shared-memory stream: the offer's token is not 32 hex digits");
  }
  if (version == offer.end() || !version->is_number_unsigned() ||
      version->get<std::uint64_t>() != shm::kVersion) {
    return R::fail(Error::kProtocol,
                   "shared-memory stream: the server offers another version of the ring");
  }
  if (bytes == offer.end() || !bytes->is_number_unsigned() ||
      shm::region_bytes(static_cast<std::size_t>(bytes->get<std::uint64_t>())) == 0) {
    return R::fail(Error::kProtocol,
                   "shared-memory stream: the offer's ring_bytes is out of range");
  }
  // the request ring after the server's, when the server gives one
  const auto request_bytes = offer.find("request_ring_bytes");
  std::size_t request_capacity = 0;
  if (request_bytes != offer.end()) {
    if (!request_bytes->is_number_unsigned() ||
        shm::region_bytes(static_cast<std::size_t>(request_bytes->get<std::uint64_t>())) == 0) {
      return R::fail(Error::kProtocol,
                     "shared-memory stream: the offer's request_ring_bytes is out of range");
    }
    request_capacity = static_cast<std::size_t>(request_bytes->get<std::uint64_t>());
  }
  const std::string t = token->get<std::string>();
  const std::string name = shm::object_name(t);
  const std::size_t ring_size =
      shm::region_bytes(static_cast<std::size_t>(bytes->get<std::uint64_t>()));
  const std::size_t size =
      ring_size + (request_capacity == 0 ? 0 : shm::region_bytes(request_capacity));

  // the region: this user's, private to it, of the size announced
  const int fd = shm_open(name.c_str(), O_RDWR | O_CLOEXEC, 0);
  if (fd < 0)
    return R::fail(Error::kIo,
                   "shared-memory stream: shm_open " + name + ": " + std::strerror(errno));
  struct stat st {};
  if (fstat(fd, &st) != 0 || st.st_uid != geteuid() || (st.st_mode & 0777) != 0600 ||
      static_cast<std::size_t>(st.st_size) != size) {
    close(fd);
    return R::fail(Error::kProtocol, "shared-memory stream: " + name +
                                         " is not this user's private region of " +
                                         std::to_string(size) + " bytes");
  }
  void* region = mmap(nullptr, size, PROT_READ | PROT_WRITE, MAP_SHARED, fd, 0);
  const int map_errno = errno;
  close(fd);
  shm_unlink(name.c_str());  // mapped: the name is no longer needed
  if (region == MAP_FAILED)
    return R::fail(Error::kIo,
                   std::string("shared-memory stream: mmap: ") + std::strerror(map_errno));

  // the wake FIFO: read end (the server holds the only write end)
  std::string fifo_error;
  const int fifo_fd = open_own_fifo(shm::fifo_path(t), O_RDONLY, &fifo_error);
  if (fifo_fd < 0) {
    munmap(region, size);
    return R::fail(Error::kIo, fifo_error);
  }
  std::string why;
  auto reader = shm::RingReader::attach(region, ring_size, &why);
  if (!reader) {
    close(fifo_fd);
    munmap(region, size);
    return R::fail(Error::kProtocol, "shared-memory stream: " + why);
  }
  std::optional<Requests> requests;
  if (request_capacity != 0) {
    // the server's wake-up FIFO, opened for reading too: a server gone leaves a FIFO with a reader
    // (this one), so a wake-up written then is lost instead of raising SIGPIPE (the socket's close
    // says the server is gone)
    std::string error;
    const int fd = open_own_fifo(shm::request_fifo_path(t), O_RDWR, &error);
    if (fd < 0) {
      close(fifo_fd);
      munmap(region, size);
      return R::fail(Error::kIo, error);
    }
    requests = Requests{
        shm::RingWriter(static_cast<std::uint8_t*>(region) + ring_size, request_capacity), fd};
  }
  return std::unique_ptr<ShmStream>(
      new ShmStream(region, size, fifo_fd, *reader, std::move(requests)));
}

ShmStream::~ShmStream() {
  munmap(region_, size_);
  close(fifo_fd_);
  if (requests_) close(requests_->fifo_fd);
}

bool ShmStream::write_request(common::shm::RecordType type, std::span<const std::uint8_t> payload,
                              double timeout_s, std::string* why, bool defer_wakeup) {
  if (!requests_) {
    *why = "no request ring";
    return false;
  }
  const std::span<const std::uint8_t> parts[] = {payload};
  const auto deadline = std::chrono::steady_clock::now() +
                        std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                            std::chrono::duration<double>(std::clamp(timeout_s, 0.0, 3600.0)));
  for (;;) {
    const auto error = requests_->writer.write(type, parts, why);
    if (!error) break;
    if (*error == shm::RingError::kTooLarge) {
      *why = "a request of " + std::to_string(payload.size()) +
             " bytes is larger than the request ring";
      return false;
    }
    if (*error == shm::RingError::kCorrupt) {
      *why = "the request ring is broken: " + *why;
      return false;
    }
    // full: the server's I/O thread, woken for what waits, is behind
    flush_wakeup();
    if (std::chrono::steady_clock::now() > deadline) {
      *why = "the request ring stayed full (the server reads no requests)";
      return false;
    }
    std::this_thread::sleep_for(std::chrono::microseconds(100));
  }
  requests_->wake_owed = true;
  if (!defer_wakeup) flush_wakeup();
  return true;
}

void ShmStream::flush_wakeup() {
  if (!requests_ || !requests_->wake_owed) return;
  requests_->wake_owed = false;
  if (requests_->writer.take_wakeup()) {
    const char b = 1;
    // a full FIFO holds a wake-up already
    (void)!::write(requests_->fifo_fd, &b, 1);
  }
}

bool ShmStream::drain_wakeups() {
  char buf[64];
  bool closed = false;
  for (;;) {
    const ssize_t n = ::read(fifo_fd_, buf, sizeof(buf));
    if (n > 0) continue;
    if (n == 0) closed = true;  // no writer left: the server closed the stream
    if (n < 0 && errno == EINTR) continue;
    break;
  }
  // cleared after the bytes are read: a record written from here on wakes the loop again
  reader_.arm();
  return closed;
}

bool ShmStream::offered_by(const nlohmann::json& hello) {
  const auto ops = hello.find("ops");
  return ops != hello.end() && ops->is_array() &&
         std::find(ops->begin(), ops->end(), "lockstep_shm") != ops->end();
}

nlohmann::json ShmStream::offer_request() {
  return {{"op", "lockstep_shm"}, {"ring_bytes", kRingBytes}, {"requests", true}};
}

bool ShmStream::peer_is_local(int socket_fd) {
  sockaddr_storage addr{};
  socklen_t len = sizeof(addr);
  if (getpeername(socket_fd, reinterpret_cast<sockaddr*>(&addr), &len) != 0) return false;
  if (addr.ss_family == AF_INET) {
    const auto* in = reinterpret_cast<const sockaddr_in*>(&addr);
    return (ntohl(in->sin_addr.s_addr) >> 24) == 127;
  }
  if (addr.ss_family == AF_INET6) {
    const auto* in6 = reinterpret_cast<const sockaddr_in6*>(&addr);
    return IN6_IS_ADDR_LOOPBACK(&in6->sin6_addr);
  }
  return false;
}

}  // namespace uavsim::client
