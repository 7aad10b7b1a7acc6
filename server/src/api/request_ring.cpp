#include "api/request_ring.hpp"

#include <unistd.h>

#include <string_view>

namespace uavsim::server::api {

namespace shm = common::shm;

std::shared_ptr<RequestRing> RequestRing::create(std::shared_ptr<void> mapping, void* region,
                                                 std::size_t capacity, int fifo_fd,
                                                 std::string* why) {
  // the header a writer starts from (the client's writer starts from the same: nothing written)
  shm::RingWriter init(region, capacity);
  auto reader = shm::RingReader::attach(region, shm::region_bytes(capacity), why);
  if (!reader) {
    close(fifo_fd);
    return nullptr;
  }
  return std::shared_ptr<RequestRing>(new RequestRing(std::move(mapping), *reader, fifo_fd));
}

RequestRing::~RequestRing() { close(fifo_fd_); }

bool RequestRing::read(const Sink& sink, std::string* why) {
  char bytes[64];
  while (::read(fifo_fd_, bytes, sizeof(bytes)) > 0) {
  }
  // cleared after the FIFO is empty: a record written from here on wakes this reader again
  reader_.arm();
  for (;;) {
    const auto status = reader_.next(&record_, why);
    if (status == shm::RingReader::Status::kEmpty) return true;
    if (status == shm::RingReader::Status::kCorrupt) {
      *why = "the client broke its request ring: " + *why;
      return false;
    }
    switch (record_.type) {
      case shm::RecordType::kStream: {
        // whole lines, each ending in a newline (an unterminated last one is a line too)
        const std::string_view text(reinterpret_cast<const char*>(record_.payload.data()),
                                    record_.payload.size());
        std::size_t start = 0;
        while (start < text.size()) {
          std::size_t end = text.find('\n', start);
          if (end == std::string_view::npos) end = text.size();
          std::string_view line = text.substr(start, end - start);
          if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
          sink.line(std::string(line));
          start = end + 1;
        }
        break;
      }
      case shm::RecordType::kRadioSend:
      case shm::RecordType::kDone:
        sink.record(static_cast<std::uint16_t>(record_.type), record_.payload);
        break;
      default:
        *why = "a record of type " + std::to_string(static_cast<int>(record_.type)) +
               " in a request ring (a client sends stream, radio_send and done records)";
        return false;
    }
  }
}

}  // namespace uavsim::server::api
