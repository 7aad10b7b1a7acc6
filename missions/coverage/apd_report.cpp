#include "apd_report.hpp"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <sstream>

namespace uavsim::missions::coverage {

std::string encode_apd_report(int agent, double time_s, const AreaParts& apd) {
  std::string out = "APD " + std::to_string(agent);
  char buf[64];
  std::snprintf(buf, sizeof buf, " %.3f ", time_s);
  out += buf;
  bool first_stripe = true;
  for (int s = 0; s < apd.stripe_count(); ++s) {
    const auto& list = apd.stripe(s);
    if (list.empty()) continue;
    if (!first_stripe) out += ';';
    first_stripe = false;
    out += std::to_string(s) + ':';
    bool first = true;
    for (const Interval& iv : list) {
      // centimetres, rounded inwards
      const long a = static_cast<long>(std::ceil(iv.start_m * 100.0 - 1e-6));
      const long b = static_cast<long>(std::floor(iv.end_m * 100.0 + 1e-6));
      if (b <= a) continue;
      if (!first) out += ',';
      first = false;
      out += std::to_string(a) + '-' + std::to_string(b);
    }
  }
  if (first_stripe) out += '-';  // nothing held yet
  return out;
}

std::optional<ApdReport> decode_apd_report(const std::string& line, int stripes) {
  if (stripes <= 0 || line.rfind("APD ", 0) != 0) return std::nullopt;
  std::istringstream in(line.substr(4));
  ApdReport r;
  std::string body;
  if (!(in >> r.agent >> r.time_s >> body) || r.agent < 0 || !std::isfinite(r.time_s)) {
    return std::nullopt;
  }
  r.apd = AreaParts(stripes);
  if (body == "-") return r;
  size_t pos = 0;
  while (pos < body.size()) {
    const size_t end = std::min(body.find(';', pos), body.size());
    const std::string item = body.substr(pos, end - pos);
    pos = end + 1;
    const size_t colon = item.find(':');
    if (colon == std::string::npos || colon == 0) return std::nullopt;
    char* e = nullptr;
    const long s = std::strtol(item.c_str(), &e, 10);
    if (e != item.c_str() + colon || s < 0 || s >= stripes) return std::nullopt;
    std::vector<Interval> list;
    size_t p = colon + 1;
    while (p < item.size()) {
      const size_t q = std::min(item.find(',', p), item.size());
      const std::string iv = item.substr(p, q - p);
      p = q + 1;
      const char* c = iv.c_str();
      const long a = std::strtol(c, &e, 10);
      if (e == c || *e != '-') return std::nullopt;
      const char* c2 = e + 1;
      const long b = std::strtol(c2, &e, 10);
      if (e == c2 || *e != '\0' || b <= a || a < 0 || b > 100000000L) return std::nullopt;
      list.push_back({a / 100.0, b / 100.0});
    }
    if (list.empty()) return std::nullopt;
    r.apd.set_stripe(static_cast<int>(s), list);
  }
  return r;
}

}  // namespace uavsim::missions::coverage
