#include "net/write_buffer.hpp"

#include <sys/socket.h>

#include <cerrno>

namespace uavsim::server::net {

WriteBuffer::Append WriteBuffer::append(std::string_view data) {
  std::lock_guard lock(mutex_);
  if (closed_) return Append::kClosed;
  if (queued_.size() + in_flight_ + data.size() > limit_bytes_) return Append::kFull;
  queued_.append(data);
  has_queued_.store(true, std::memory_order_release);
  return Append::kQueued;
}

void WriteBuffer::append_unbounded(std::string_view data) {
  std::lock_guard lock(mutex_);
  if (closed_) return;
  queued_.append(data);
  has_queued_.store(true, std::memory_order_release);
}

WriteBuffer::Write WriteBuffer::write_to(int fd, std::size_t* written) {
  for (;;) {
    if (sent_ >= sending_.size()) {
      // the next batch: swap, so the emptied string takes the next bytes without reallocating
      sending_.clear();
      sent_ = 0;
      std::lock_guard lock(mutex_);
      sending_.swap(queued_);
      in_flight_ = sending_.size();
      has_queued_.store(false, std::memory_order_release);
      if (sending_.empty()) return Write::kDone;
    }
    const ssize_t n =
        ::send(fd, sending_.data() + sent_, sending_.size() - sent_, MSG_NOSIGNAL | MSG_DONTWAIT);
    if (n < 0) {
      if (errno == EINTR) continue;
      return errno == EAGAIN || errno == EWOULDBLOCK ? Write::kBlocked : Write::kFailed;
    }
    sent_ += static_cast<std::size_t>(n);
    *written += static_cast<std::size_t>(n);
    std::lock_guard lock(mutex_);
    in_flight_ = sending_.size() - sent_;
  }
}

void WriteBuffer::take_queued(std::string& out) {
  out.clear();
  std::lock_guard lock(mutex_);
  out.swap(queued_);
  has_queued_.store(false, std::memory_order_release);
}

std::size_t WriteBuffer::unwritten() const {
  std::lock_guard lock(mutex_);
  return queued_.size() + in_flight_;
}

void WriteBuffer::close() {
  std::lock_guard lock(mutex_);
  closed_ = true;
  queued_.clear();
  has_queued_.store(false, std::memory_order_release);
}

}  // namespace uavsim::server::net
