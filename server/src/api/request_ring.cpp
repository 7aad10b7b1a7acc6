#include "api/request_ring.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <string_view>

namespace uavsim::server::api {

namespace shm = common::shm;

std::shared_ptr<RequestRing> RequestRing::create(std::shared_ptr<void> mapping, void* region,
                                                 std::size_t capacity, std::string fifo_path,
                                                 std::string* why) {
  // the header a writer starts from (the client's writer starts from the same: nothing written)
  shm::RingWriter init(region, capacity);
  auto reader = shm::RingReader::attach(region, shm::region_bytes(capacity), why);
  if (!reader) return nullptr;
  int fd = -1;
  if (mkfifo(fifo_path.c_str(), 0600) == 0)
    fd = open(fifo_path.c_str(), O_RDWR | O_NONBLOCK | O_CLOEXEC);
  if (fd < 0) {
    *why = "FIFO " + fifo_path + ": " + std::strerror(errno);
    unlink(fifo_path.c_str());
    return nullptr;
  }
  return std::shared_ptr<RequestRing>(
      new RequestRing(std::move(mapping), *reader, std::move(fifo_path), fd));
}

RequestRing::~RequestRing() {
  unlink(fifo_path_.c_str());  // (gone already once the client has opened it)
  close(fifo_fd_);
}

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
