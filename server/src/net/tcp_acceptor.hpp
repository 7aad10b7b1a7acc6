// A listening TCP socket on an EventLoop, and the reserve descriptor that keeps it from spinning
// when the process runs out of file descriptors (muduo's Acceptor and its idleFd_).
#pragma once

#include <netinet/in.h>

#include <atomic>
#include <cstdint>
#include <functional>
#include <string>

#include "net/event_loop.hpp"

namespace uavsim::server::net {

// One spare descriptor (/dev/null) held back for the moment accept() fails with EMFILE/ENFILE: the
// waiting connection would keep the level-triggered listener readable and the loop spinning, so the
// spare is given up to accept it, the connection is closed at once and the spare is taken back. One
// reserve serves every acceptor of a loop (they accept one at a time on its thread). I/O thread
// only.
class FdReserve {
 public:
  FdReserve();
  ~FdReserve();
  FdReserve(const FdReserve&) = delete;
  FdReserve& operator=(const FdReserve&) = delete;

  // Accepts one waiting connection on listen_fd with the spare and closes it. True if one was
  // waiting (then the caller tries again), false if the queue was empty or the spare is lost.
  bool accept_and_drop(int listen_fd);
  // Takes the spare back after a failure that lost it (another thread took the freed number).
  void restore();

 private:
  int fd_ = -1;
};

// The IPv4 address host:port; false if host is not a dotted IPv4 address.
bool ipv4_address(const std::string& host, int port, sockaddr_in* out);
// "ADDR:PORT" of an IPv4 socket address, and "ADDR" alone.
std::string address_text(const sockaddr_in& address);
std::string ip_text(const sockaddr_in& address);

class TcpAcceptor {
 public:
  // a new connection: fd is non-blocking and close-on-exec, and owned by the callee from now on
  using OnAccept = std::function<void(int fd, const sockaddr_in& peer)>;

  // Binds address:port (port 0: ephemeral) and listens with backlog; nothing is accepted before
  // start(). Throws std::runtime_error "WHAT: cannot listen on ADDR:PORT: REASON" or "WHAT: bad
  // bind address 'ADDR' (an IPv4 address)" (startup errors). Any thread.
  TcpAcceptor(EventLoop& loop, FdReserve& reserve, const std::string& address, int port,
              int backlog, const std::string& what, OnAccept on_accept);
  // Stops watching and closes the listening socket. I/O thread, or when the loop does not run.
  ~TcpAcceptor();

  // Watches for connections: on_accept runs on the I/O thread. I/O thread or before it starts.
  void start();
  // Stops watching: on_accept is not called again. I/O thread, or when the loop does not run.
  void stop();
  TcpAcceptor(const TcpAcceptor&) = delete;
  TcpAcceptor& operator=(const TcpAcceptor&) = delete;

  // The bound port. Thread-safe.
  std::uint16_t port() const { return port_; }
  // Connections accepted on the reserve and closed because no descriptor was left. Thread-safe.
  std::uint64_t exhausted_accepts() const { return exhausted_accepts_.load(); }

 private:
  void accept_all();

  EventLoop& loop_;
  FdReserve& reserve_;
  OnAccept on_accept_;
  int fd_ = -1;
  bool watched_ = false;
  std::uint16_t port_ = 0;
  std::atomic<std::uint64_t> exhausted_accepts_{0};
};

}  // namespace uavsim::server::net
