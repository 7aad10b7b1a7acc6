#include "mavlink/tlog.hpp"

#include <algorithm>
#include <cmath>
#include <iterator>
#include <stdexcept>

namespace uavsim::server::mavlink {

std::size_t frame_length(std::span<const std::uint8_t> bytes) {
  if (bytes.size() < 3) return 0;
  // v1: 6 header bytes, payload, CRC; v2: 10 header bytes, payload, CRC, 13 signature bytes if signed
  if (bytes[0] == 0xFE) return 6 + std::size_t{bytes[1]} + 2;
  if (bytes[0] == 0xFD) return 10 + std::size_t{bytes[1]} + 2 + ((bytes[2] & 0x01) != 0 ? 13 : 0);
  return 0;
}

TlogWriter::TlogWriter(const std::string& path) : path_(path), out_(path, std::ios::binary | std::ios::trunc) {
  if (!out_) throw std::runtime_error("cannot write the telemetry log " + path);
}

void TlogWriter::write(double t_s, std::span<const std::uint8_t> frame) {
  // sim time in microseconds, kept monotonic across a restart of the sim clock
  const auto sim_us = static_cast<std::uint64_t>(std::llround(std::max(0.0, t_s) * 1e6));
  if (sim_us + offset_us_ < last_stamp_us_) offset_us_ = last_stamp_us_ - sim_us;
  const std::uint64_t stamp = sim_us + offset_us_;
  last_stamp_us_ = stamp;
  std::uint8_t be[8];
  for (int i = 0; i < 8; ++i) be[i] = static_cast<std::uint8_t>(stamp >> (56 - 8 * i));
  out_.write(reinterpret_cast<const char*>(be), sizeof(be));
  out_.write(reinterpret_cast<const char*>(frame.data()), static_cast<std::streamsize>(frame.size()));
  ++frames_;
}

void TlogWriter::flush() { out_.flush(); }

std::vector<TlogRecord> read_tlog(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  const std::vector<std::uint8_t> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  std::vector<TlogRecord> records;
  std::size_t at = 0;
  while (at + 8 < bytes.size()) {
    TlogRecord r;
    for (int i = 0; i < 8; ++i) r.stamp_us = (r.stamp_us << 8) | bytes[at + i];
    const std::span<const std::uint8_t> rest(bytes.data() + at + 8, bytes.size() - at - 8);
    const std::size_t len = frame_length(rest);
    if (len == 0 || len > rest.size()) break;
    r.frame.assign(rest.begin(), rest.begin() + static_cast<long>(len));
    records.push_back(std::move(r));
    at += 8 + len;
  }
  return records;
}

}  // namespace uavsim::server::mavlink
