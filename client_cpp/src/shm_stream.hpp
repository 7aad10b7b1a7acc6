// The client's end of the sim API's shared-memory stream (docs/protocol.md, "Shared-memory stream";
// the ring itself: common/shm_ring.hpp). For a lockstep loop on the server's machine, everything
// the server sends the connection arrives through a ring in shared memory, with a FIFO as the
// wake-up the event loop waits on. SimChannel reads it in place of the socket. With the request
// ring the server offers beside it, every request goes the other way through shared memory too (a
// FIFO byte waking the server's I/O thread), radio_send and done in their binary forms
// (common/shm_requests.hpp); without it, requests go on TCP.
//
// Library internal; loop thread only.
#pragma once

#include <cstddef>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <span>
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

  // Whether the server gave this stream a request ring.
  bool has_requests() const { return requests_.has_value(); }
  // Writes one request record (a kStream record holds whole lines, each with its newline) and wakes
  // the server if it is not awake for it already, or with defer_wakeup leaves that to
  // flush_wakeup(), which a writer must call before it sleeps (a lockstep loop's tick of requests
  // then wakes the server once). A full ring is waited on (the server, woken, reads it on its I/O
  // thread) for at most timeout_s of wall time. False with *why if it cannot be written: no request
  // ring, a record larger than the ring, the ring broken, or the wait out.
  bool write_request(common::shm::RecordType type, std::span<const std::uint8_t> payload,
                     double timeout_s, std::string* why, bool defer_wakeup = false);
  void flush_wakeup();

  // Whether the socket's peer is on this machine (a loopback address): only then is the stream
  // offered.
  static bool peer_is_local(int socket_fd);
  // Whether a server's hello lists the op that offers the stream (lockstep_shm).
  static bool offered_by(const nlohmann::json& hello);
  // The request for the stream, with the ring this client asks for and its request ring.
  static nlohmann::json offer_request();

 private:
  struct Requests {
    common::shm::RingWriter writer;
    int fifo_fd;             // the write end of the server's wake-up FIFO
    bool wake_owed = false;  // records written with defer_wakeup, the server not woken for them
  };
  ShmStream(void* region, std::size_t size, int fifo_fd, common::shm::RingReader reader,
            std::optional<Requests> requests)
      : region_(region),
        size_(size),
        fifo_fd_(fifo_fd),
        reader_(reader),
        requests_(std::move(requests)) {}
  void* region_;
  std::size_t size_;
  int fifo_fd_;
  common::shm::RingReader reader_;
  std::optional<Requests> requests_;
};

}  // namespace uavsim::client
