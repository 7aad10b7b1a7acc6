// The server's end of a client's request ring (docs/protocol.md, "Shared-memory stream"): a
// lockstep client on this machine writes its requests into a ring in the region its shared-memory
// stream shares (common/shm_ring.hpp; the binary radio_send and done: common/shm_requests.hpp) and
// wakes the server through a FIFO, instead of sending lines on TCP: no socket write, no TCP stack,
// and no JSON or base64 for the two requests it sends every tick. The line server reads it on its
// I/O thread as a second way in for the connection (LineServer::Intake): the ring's lines go where
// the socket's do, its binary requests to the sim API's on_record.
//
// Wake-ups mirror the server's ring: the server clears the ring's flag after it has emptied the
// FIFO and before it looks for records; the client writes a FIFO byte when it finds the flag clear.
// A ring that breaks the protocol (a position outside what was written, a record of a type a client
// may not send) closes the connection.
#pragma once

#include <cstddef>
#include <memory>
#include <string>

#include "api/line_server.hpp"
#include "uavsim/common/shm_ring.hpp"

namespace uavsim::server::api {

class RequestRing : public LineServer::Intake {
 public:
  // Sets up the ring at region (its header, then capacity bytes) for the client to write; fifo_fd is
  // the client's wake-up FIFO, which it takes (the transport makes and names it, held open for
  // reading and writing, so that a client that goes never makes it readable). mapping keeps region
  // mapped while the ring is in use. nullptr with *why (fifo_fd closed) if the ring cannot be read.
  static std::shared_ptr<RequestRing> create(std::shared_ptr<void> mapping, void* region,
                                             std::size_t capacity, int fifo_fd, std::string* why);
  ~RequestRing() override;  // closes the FIFO
  RequestRing(const RequestRing&) = delete;
  RequestRing& operator=(const RequestRing&) = delete;

  int fd() const override { return fifo_fd_; }
  bool read(const Sink& sink, std::string* why) override;

 private:
  RequestRing(std::shared_ptr<void> mapping, common::shm::RingReader reader, int fifo_fd)
      : mapping_(std::move(mapping)), reader_(reader), fifo_fd_(fifo_fd) {}
  std::shared_ptr<void> mapping_;
  common::shm::RingReader reader_;
  common::shm::RingReader::Record record_;  // reused between records
  int fifo_fd_;
};

}  // namespace uavsim::server::api
