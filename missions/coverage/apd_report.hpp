// The agent program's report of its Area Parts Database on its standard output, which the
// launcher (coverage-run) reads to score the data that survived: the pictures held by the agents
// still alive at the end. A report is one line of text:
//
//   APD <agent> <time_s> <stripe>:<start_m>-<end_m>[,<start_m>-<end_m>...][;<stripe>:...]
//
// with only the stripes that hold something, ends in centimetres rounded inwards (a report never
// claims more than the agent holds). Pure: no I/O.
#pragma once

#include <optional>
#include <string>

#include "area_parts.hpp"

namespace uavsim::missions::coverage {

struct ApdReport {
  int agent = -1;
  double time_s = 0.0;
  AreaParts apd;
};

std::string encode_apd_report(int agent, double time_s, const AreaParts& apd);
// A line as encode_apd_report writes it, for a rectangle of `stripes` stripes; nothing when the
// line is not a report or is malformed (a stripe out of range, an inverted interval, junk).
std::optional<ApdReport> decode_apd_report(const std::string& line, int stripes);

}  // namespace uavsim::missions::coverage
