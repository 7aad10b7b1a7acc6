// The client's end of the sim API's shared-memory stream (docs/protocol.md, "Shared-memory stream";
// the ring itself: common/shm_ring.hpp). For a lockstep loop on the server's machine, everything
// the server sends the connection arrives through a ring in shared memory, with a FIFO as the
// wake-up the event loop waits on; requests still go on TCP. SimChannel reads it in place of the
// socket.
//
// Library internal; loop thread only.
#pragma once

#include <cstddef>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>

#include "uavsim/client/result.hpp"
#include "uavsim/common/shm_ring.hpp"

namespace uavsim::client {

class ShmStream {
 public:
  // The ring asked for: as the server's default, room for many ticks and a dozen camera frames.
  static constexpr std::size_t kRingBytes = std::size_t{16} << 20;

  // Opens what a lockstep_shm reply offered ({token, ring_bytes, version}): maps the region (it
  // must be this user's, 0600, of the announced size), opens the wake FIFO, and unlinks both names.
  // kProtocol for an offer out of range, kIo when the system refuses.
  static Result<std::unique_ptr<ShmStream>> open(const nlohmann::json& offer);
  ~ShmStream();
  ShmStream(const ShmStream&) = delete;
  ShmStream& operator=(const ShmStream&) = delete;

  // The descriptor to wait on (readable: records may wait; hang-up: the server closed the stream).
  int wake_fd() const { return fifo_fd_; }
  // Reads the pending wake-ups and arms the next one; true if the server has closed its end.
  bool drain_wakeups();
  // The next record (see RingReader::next).
  common::shm::RingReader::Status next(common::shm::RingReader::Record* out, std::string* why) {
    return reader_.next(out, why);
  }

  // Whether the socket's peer is on this machine (a loopback address): only then is the stream
  // offered.
  static bool peer_is_local(int socket_fd);
  // Whether a server's hello lists the op that offers the stream (lockstep_shm).
  static bool offered_by(const nlohmann::json& hello);
  // The request for the stream, with the ring this client asks for.
  static nlohmann::json offer_request();

 private:
  ShmStream(void* region, std::size_t size, int fifo_fd, common::shm::RingReader reader)
      : region_(region), size_(size), fifo_fd_(fifo_fd), reader_(reader) {}
  void* region_;
  std::size_t size_;
  int fifo_fd_;
  common::shm::RingReader reader_;
};

}  // namespace uavsim::client
