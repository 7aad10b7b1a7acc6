// The shared-memory records' field codec (shm_ring.cpp's tick records, shm_requests.cpp's request
// records): fixed-size fields in the host's byte order appended to a buffer, and a reader that
// never reads past its payload. Internal to uavsim_common.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <span>
#include <vector>

namespace uavsim::common::shm::codec {

template <typename T>
void append(std::vector<std::uint8_t>* out, T value) {
  const std::size_t at = out->size();
  out->resize(at + sizeof(T));
  std::memcpy(out->data() + at, &value, sizeof(T));
}

// a bounds-checked reader of a payload
class Cursor {
 public:
  explicit Cursor(std::span<const std::uint8_t> bytes) : bytes_(bytes) {}
  template <typename T>
  bool take(T* out) {
    if (bytes_.size() - pos_ < sizeof(T)) return false;
    std::memcpy(out, bytes_.data() + pos_, sizeof(T));
    pos_ += sizeof(T);
    return true;
  }
  bool take_bytes(std::size_t n, std::vector<std::uint8_t>* out) {
    if (bytes_.size() - pos_ < n) return false;
    out->assign(bytes_.begin() + static_cast<std::ptrdiff_t>(pos_),
                bytes_.begin() + static_cast<std::ptrdiff_t>(pos_ + n));
    pos_ += n;
    return true;
  }
  std::size_t left() const { return bytes_.size() - pos_; }

 private:
  std::span<const std::uint8_t> bytes_;
  std::size_t pos_ = 0;
};

}  // namespace uavsim::common::shm::codec
