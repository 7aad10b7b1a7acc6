// The GCS link settings the coverage programs share (coverage-agent's uplink, coverage-gcs): the
// client's GCS link (seed 6.3) with room for a whole APD in one message.
#pragma once

#include <cstddef>
#include <cstdint>

#include "uavsim/client/gcs_link.hpp"

namespace uavsim::missions::coverage {

// An APD or map of a large rectangle flown with gaps is a few KiB (radio_messages.hpp, encode_apd):
// more than the link's default payload; UDP carries it in one datagram.
inline constexpr size_t kStationMaxMessageBytes = 32768;

inline client::GcsLinkConfig station_link_config(uint8_t local_id) {
  client::GcsLinkConfig c;
  c.local_id = local_id;
  c.max_payload_bytes = kStationMaxMessageBytes;
  c.max_packet_bytes = kStationMaxMessageBytes + 1024;
  return c;
}

}  // namespace uavsim::missions::coverage
