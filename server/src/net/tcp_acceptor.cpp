#include "net/tcp_acceptor.hpp"

#include <arpa/inet.h>
#include <fcntl.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <stdexcept>

namespace uavsim::server::net {

namespace {

int open_spare() { return ::open("/dev/null", O_RDONLY | O_CLOEXEC); }

}  // namespace

FdReserve::FdReserve() : fd_(open_spare()) {}

FdReserve::~FdReserve() {
  if (fd_ >= 0) close(fd_);
}

bool FdReserve::accept_and_drop(int listen_fd) {
  if (fd_ < 0) {
    fd_ = open_spare();  // lost earlier: try to take it back for the next time
    return false;
  }
  // accept reports EMFILE before it looks at the queue, so an empty queue shows only here
  close(fd_);
  const int doomed = accept(listen_fd, nullptr, nullptr);
  if (doomed >= 0) close(doomed);
  fd_ = open_spare();
  return doomed >= 0;
}

void FdReserve::restore() {
  if (fd_ < 0) fd_ = open_spare();
}

bool ipv4_address(const std::string& host, int port, sockaddr_in* out) {
  *out = sockaddr_in{};
  out->sin_family = AF_INET;
  out->sin_port = htons(static_cast<std::uint16_t>(port));
  return inet_pton(AF_INET, host.c_str(), &out->sin_addr) == 1;
}

std::string ip_text(const sockaddr_in& address) {
  char ip[INET_ADDRSTRLEN] = {};
  inet_ntop(AF_INET, &address.sin_addr, ip, sizeof(ip));
  return ip;
}

std::string address_text(const sockaddr_in& address) {
  return ip_text(address) + ":" + std::to_string(ntohs(address.sin_port));
}

TcpAcceptor::TcpAcceptor(EventLoop& loop, FdReserve& reserve, const std::string& address, int port,
                         int backlog, const std::string& what, OnAccept on_accept)
    : loop_(loop), reserve_(reserve), on_accept_(std::move(on_accept)) {
  const std::string where = address + ":" + std::to_string(port);
  sockaddr_in sa{};
  if (!ipv4_address(address, port, &sa)) {
    throw std::runtime_error(what + ": bad bind address '" + address + "' (an IPv4 address)");
  }
  fd_ = socket(AF_INET, SOCK_STREAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
  if (fd_ < 0) throw std::runtime_error(what + ": socket() failed for " + where);
  const int one = 1;
  setsockopt(fd_, SOL_SOCKET, SO_REUSEADDR, &one, sizeof(one));
  if (bind(fd_, reinterpret_cast<sockaddr*>(&sa), sizeof(sa)) != 0 || listen(fd_, backlog) != 0) {
    const std::string err = std::strerror(errno);
    close(fd_);
    throw std::runtime_error(what + ": cannot listen on " + where + ": " + err);
  }
  socklen_t len = sizeof(sa);
  getsockname(fd_, reinterpret_cast<sockaddr*>(&sa), &len);
  port_ = ntohs(sa.sin_port);
}

TcpAcceptor::~TcpAcceptor() {
  stop();
  close(fd_);
}

void TcpAcceptor::start() {
  watched_ = true;
  loop_.watch(fd_, EPOLLIN, [this](std::uint32_t) { accept_all(); });
}

void TcpAcceptor::stop() {
  if (watched_) loop_.unwatch(fd_);
  watched_ = false;
}

void TcpAcceptor::accept_all() {
  for (;;) {
    sockaddr_in peer{};
    socklen_t peer_len = sizeof(peer);
    const int fd =
        accept4(fd_, reinterpret_cast<sockaddr*>(&peer), &peer_len, SOCK_NONBLOCK | SOCK_CLOEXEC);
    if (fd >= 0) {
      on_accept_(fd, peer);
      continue;
    }
    if (errno == EMFILE || errno == ENFILE) {
      // out of descriptors: drop the waiting connection on the reserve, not spin on it
      if (!reserve_.accept_and_drop(fd_)) return;
      exhausted_accepts_.fetch_add(1);
      continue;
    }
    // EAGAIN, or a transient error (ECONNABORTED): try at the next event; a reserve lost to a race
    // with another thread is taken back now that descriptors may be free
    reserve_.restore();
    return;
  }
}

}  // namespace uavsim::server::net
