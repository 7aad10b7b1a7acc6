#include "net.hpp"

#include <arpa/inet.h>
#include <fcntl.h>
#include <netdb.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstring>

namespace uavsim::client::net {

namespace {
int ms_left(std::chrono::steady_clock::time_point end) {
  const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(end - std::chrono::steady_clock::now());
  return static_cast<int>(std::max<std::int64_t>(0, left.count()));
}
std::chrono::steady_clock::time_point deadline(double timeout_s) {
  return std::chrono::steady_clock::now() +
         std::chrono::duration_cast<std::chrono::steady_clock::duration>(std::chrono::duration<double>(timeout_s));
}
}  // namespace

bool parse_address(const std::string& address, std::string* host, int* port) {
  std::string a = address;
  if (a.rfind("tcp:", 0) == 0) a = a.substr(4);
  const auto colon = a.rfind(':');
  std::string h = colon == std::string::npos ? "" : a.substr(0, colon);
  const std::string p = colon == std::string::npos ? a : a.substr(colon + 1);
  char* end = nullptr;
  const long v = std::strtol(p.c_str(), &end, 10);
  if (p.empty() || *end != '\0' || v <= 0 || v > 65535) return false;
  *host = h.empty() ? "127.0.0.1" : h;
  *port = static_cast<int>(v);
  return true;
}

std::optional<LinkAddress> parse_link_address(const std::string& address) {
  LinkAddress a;
  std::string rest = address;
  if (rest.rfind("udpin:", 0) == 0) {
    a.kind = LinkAddress::Kind::kUdpIn;
    rest = rest.substr(6);
  } else if (rest.rfind("udp:", 0) == 0) {
    a.kind = LinkAddress::Kind::kUdp;
    rest = rest.substr(4);
  }
  if (rest.rfind("tcp:", 0) == 0) rest = rest.substr(4);
  // one colon at most is left: an unknown scheme ("udpx:HOST:PORT") is not a host name
  if (std::count(rest.begin(), rest.end(), ':') > 1) return std::nullopt;
  if (!parse_address(rest, &a.host, &a.port)) return std::nullopt;
  return a;
}

// host:port as an IPv4 address (the first the resolver gives); kInvalidArgument if it cannot resolve
Result<sockaddr_in> resolve_ipv4(const std::string& host, int port) {
  addrinfo hints{};
  hints.ai_family = AF_INET;
  addrinfo* res = nullptr;
  if (getaddrinfo(host.c_str(), std::to_string(port).c_str(), &hints, &res) != 0 || res == nullptr) {
    return Result<sockaddr_in>::fail(Error::kInvalidArgument, "cannot resolve " + host + ":" + std::to_string(port));
  }
  sockaddr_in sa{};
  std::memcpy(&sa, res->ai_addr, sizeof(sa));
  freeaddrinfo(res);
  return sa;
}

Result<int> udp_open(const std::string& host, int port, bool listen) {
  const std::string where = host + ":" + std::to_string(port);
  const auto sa = resolve_ipv4(host, port);
  if (!sa) return Result<int>(sa.error());
  const int fd = ::socket(AF_INET, SOCK_DGRAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
  if (fd < 0) return Result<int>::fail(Error::kIo, std::string("socket: ") + std::strerror(errno));
  const auto* addr = reinterpret_cast<const sockaddr*>(&*sa);
  if ((listen ? ::bind(fd, addr, sizeof(*sa)) : ::connect(fd, addr, sizeof(*sa))) != 0) {
    const int err = errno;
    ::close(fd);
    return Result<int>::fail(Error::kIo, std::string(listen ? "cannot listen on udp:" : "cannot send to udp:") +
                                             where + ": " + std::strerror(err));
  }
  return fd;
}

Result<int> tcp_connect(const std::string& host, int port, double timeout_s) {
  const std::string where = host + ":" + std::to_string(port);
  const auto sa = resolve_ipv4(host, port);
  if (!sa) return Result<int>(sa.error());
  const int fd = ::socket(AF_INET, SOCK_STREAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
  if (fd < 0) return Result<int>::fail(Error::kIo, std::string("socket: ") + std::strerror(errno));
  const int one = 1;
  setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof(one));
  int rc = ::connect(fd, reinterpret_cast<const sockaddr*>(&*sa), sizeof(*sa));
  int err = rc == 0 ? 0 : errno;
  if (err == EINPROGRESS) {
    pollfd p{fd, POLLOUT, 0};
    const auto end = deadline(timeout_s);
    int n;
    do {
      n = ::poll(&p, 1, ms_left(end));
    } while (n < 0 && errno == EINTR);
    if (n == 0) {
      ::close(fd);
      return Result<int>::fail(Error::kTimeout, "connecting to " + where + ": no answer within " +
                                                    std::to_string(timeout_s) + " s");
    }
    socklen_t len = sizeof(err);
    getsockopt(fd, SOL_SOCKET, SO_ERROR, &err, &len);
  }
  if (err != 0) {
    ::close(fd);
    if (err == ECONNREFUSED) return Result<int>::fail(Error::kConnectionRefused, "connection refused by " + where);
    if (err == ETIMEDOUT) return Result<int>::fail(Error::kTimeout, "connecting to " + where + " timed out");
    return Result<int>::fail(Error::kIo, "connecting to " + where + ": " + std::strerror(err));
  }
  return fd;
}

bool send_all(int fd, const void* data, std::size_t size, double timeout_s) {
  const auto* p = static_cast<const char*>(data);
  std::size_t off = 0;
  const auto end = deadline(timeout_s);
  while (off < size) {
    const ssize_t n = ::send(fd, p + off, size - off, MSG_NOSIGNAL | MSG_DONTWAIT);
    if (n > 0) {
      off += static_cast<std::size_t>(n);
      continue;
    }
    if (n < 0 && errno == EINTR) continue;
    if (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK)) {
      pollfd pf{fd, POLLOUT, 0};
      if (::poll(&pf, 1, ms_left(end)) <= 0 && ms_left(end) == 0) return false;
      continue;
    }
    return false;
  }
  return true;
}

bool send_all(int fd, const std::string& data, double timeout_s) {
  return send_all(fd, data.data(), data.size(), timeout_s);
}

Result<std::string> read_line(int fd, std::string& buf, double timeout_s) {
  const auto end = deadline(timeout_s);
  for (;;) {
    const auto nl = buf.find('\n');
    if (nl != std::string::npos) {
      std::string line = buf.substr(0, nl);
      buf.erase(0, nl + 1);
      return line;
    }
    pollfd p{fd, POLLIN, 0};
    const int n = ::poll(&p, 1, ms_left(end));
    if (n < 0 && errno == EINTR) continue;
    if (n == 0) return Result<std::string>::fail(Error::kTimeout, "no reply within " + std::to_string(timeout_s) + " s");
    char tmp[65536];
    const ssize_t r = ::recv(fd, tmp, sizeof(tmp), MSG_DONTWAIT);
    if (r == 0) return Result<std::string>::fail(Error::kConnectionLost, "connection closed by the peer");
    if (r < 0) {
      if (errno == EAGAIN || errno == EINTR) continue;
      return Result<std::string>::fail(Error::kIo, std::string("recv: ") + std::strerror(errno));
    }
    buf.append(tmp, static_cast<std::size_t>(r));
  }
}

}  // namespace uavsim::client::net
