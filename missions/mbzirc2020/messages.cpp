#include "messages.hpp"

#include <cmath>
#include <cstring>
#include <limits>

namespace uavsim::missions::mbzirc2020 {
namespace {

void put_double(std::vector<uint8_t>& out, double v) {
  uint64_t bits;
  std::memcpy(&bits, &v, sizeof(bits));
  for (int i = 7; i >= 0; --i) out.push_back(static_cast<uint8_t>(bits >> (8 * i)));
}

double get_double(const std::vector<uint8_t>& in, size_t at) {
  uint64_t bits = 0;
  for (size_t i = 0; i < 8; ++i) bits = (bits << 8) | in[at + i];
  double v;
  std::memcpy(&v, &bits, sizeof(v));
  return v;
}

}  // namespace

std::vector<uint8_t> encode_command(GcsCommand c) { return {static_cast<uint8_t>(c)}; }

std::optional<GcsCommand> decode_command(const std::vector<uint8_t>& p) {
  if (p.size() != 1 || p[0] < 1 || p[0] > 4) return std::nullopt;
  return static_cast<GcsCommand>(p[0]);
}

std::vector<uint8_t> encode_airspace(const std::optional<AirspaceArea>& a) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double v[4] = {a ? a->from_enu_m.x() : nan, a ? a->from_enu_m.y() : nan,
                       a ? a->to_enu_m.x() : nan, a ? a->to_enu_m.y() : nan};
  std::vector<uint8_t> out;
  for (double x : v) put_double(out, x);
  return out;
}

std::optional<std::optional<AirspaceArea>> decode_airspace(const std::vector<uint8_t>& p) {
  if (p.size() != 32) return std::nullopt;
  double v[4];
  bool any_nan = false;
  for (int i = 0; i < 4; ++i) {
    v[i] = get_double(p, 8 * static_cast<size_t>(i));
    any_nan = any_nan || std::isnan(v[i]);
  }
  if (any_nan) return std::optional<AirspaceArea>();
  return std::optional<AirspaceArea>(AirspaceArea{{v[0], v[1]}, {v[2], v[3]}});
}

std::vector<uint8_t> encode_status(const UavStatus& s) {
  std::vector<uint8_t> out{
      s.state, static_cast<uint8_t>((s.ready ? 1 : 0) | (s.failed ? 2 : 0) | (s.landed ? 4 : 0)),
      s.popped};
  for (int i = 0; i < 3; ++i) put_double(out, s.position_enu_m[i]);
  return out;
}

std::optional<UavStatus> decode_status(const std::vector<uint8_t>& p) {
  if (p.size() != 27) return std::nullopt;
  UavStatus s;
  s.state = p[0];
  s.ready = (p[1] & 1) != 0;
  s.failed = (p[1] & 2) != 0;
  s.landed = (p[1] & 4) != 0;
  s.popped = p[2];
  for (int i = 0; i < 3; ++i) s.position_enu_m[i] = get_double(p, 3 + 8 * static_cast<size_t>(i));
  return s;
}

std::vector<uint8_t> encode_point(const Eigen::Vector2d& p_enu_m) {
  std::vector<uint8_t> out;
  put_double(out, p_enu_m.x());
  put_double(out, p_enu_m.y());
  return out;
}

std::optional<Eigen::Vector2d> decode_point(const std::vector<uint8_t>& p) {
  if (p.size() != 16) return std::nullopt;
  return Eigen::Vector2d(get_double(p, 0), get_double(p, 8));
}

}  // namespace uavsim::missions::mbzirc2020
