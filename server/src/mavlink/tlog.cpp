#include "mavlink/tlog.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <iterator>
#include <stdexcept>

namespace uavsim::server::mavlink {

std::size_t frame_length(std::span<const std::uint8_t> bytes) {
  if (bytes.size() < 3) return 0;
  // v1: 6 header bytes, payload, CRC; v2: 10 header bytes, payload, CRC, 13 signature bytes if
  // signed
  if (bytes[0] == 0xFE) return 6 + std::size_t{bytes[1]} + 2;
  if (bytes[0] == 0xFD) return 10 + std::size_t{bytes[1]} + 2 + ((bytes[2] & 0x01) != 0 ? 13 : 0);
  return 0;
}

TlogWriter::TlogWriter(const std::string& path) : path_(path) {
  if (std::string why; !file_.open(path, &why)) throw std::runtime_error("telemetry log: " + why);
}

TlogWriter::~TlogWriter() { (void)flush(); }

void TlogWriter::write(double t_s, std::span<const std::uint8_t> frame) {
  // sim time in microseconds, kept monotonic across a restart of the sim clock
  const auto sim_us = static_cast<std::uint64_t>(std::llround(std::max(0.0, t_s) * 1e6));
  if (sim_us + offset_us_ < last_stamp_us_) offset_us_ = last_stamp_us_ - sim_us;
  const std::uint64_t stamp = sim_us + offset_us_;
  last_stamp_us_ = stamp;
  // the records older than the bound go first, so the file never lags more than kFlushSpan_s
  if (!pending_.empty() &&
      stamp - pending_since_us_ >= static_cast<std::uint64_t>(kFlushSpan_s * 1e6))
    (void)flush();
  if (pending_.empty()) pending_since_us_ = stamp;
  for (int i = 0; i < 8; ++i) pending_.push_back(static_cast<char>(stamp >> (56 - 8 * i)));
  pending_.append(reinterpret_cast<const char*>(frame.data()), frame.size());
  ++frames_;
  if (pending_.size() >= kFlushBytes) (void)flush();
}

bool TlogWriter::flush() {
  const bool ok = pending_.empty() ? file_.error().empty() : file_.write(pending_);
  pending_.clear();
  return ok;
}

std::vector<TlogRecord> read_tlog(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  const std::vector<std::uint8_t> bytes((std::istreambuf_iterator<char>(in)),
                                        std::istreambuf_iterator<char>());
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
