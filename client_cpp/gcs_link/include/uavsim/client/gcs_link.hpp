// The ground-station link (seed 6.3): a small reliable protocol over UDP between a UAV and its
// Ground Control Station. The same code runs on a real UAV, on the ground station and in
// simulation.
//   - Every message belongs to a 16-bit topic. Topics 0x8000-0xffff are "latest only": publishing a
//   new
//     message drops the unsent or unacknowledged older one of that topic (a stale position is not
//     worth retransmitting); topics 0x0000-0x7fff queue every message.
//   - Once per period (10 Hz by default) one UDP packet carries the acknowledgements of the
//   messages
//     received from the peer and every message not yet acknowledged (first sends and
//     retransmissions), oldest first, up to max_packet_bytes; the rest waits for the next period.
//   - The GCS (id 255) writes its clock in every packet; the UAV (ids 0-254) estimates the offset
//   of its
//     clock from the GCS's with Algorithm 6: the least (local receive time - GCS send time) seen,
//     whose error is the shortest propagation delay observed (clock drift neglected, seed note 31).
//
// Packet (all integers big-endian): header {magic 'U''G', version 1, sender id, GCS time in us (0
// from a UAV), low-water id (every message id below it will never be sent again), ack count,
// message count}, then ack records {message id: u32}, then message records {id: u32, topic: u16,
// length: u16, payload}.
//
// GcsLinkCore is the protocol alone: no sockets, no clock (time is passed in). GcsLink is its UDP
// adapter.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace uavsim::client {

inline constexpr uint8_t kGcsId = 255;  // seed 6.3, note 33: UAVs are 0-254
inline constexpr uint16_t kLatestOnlyTopicBit = 0x8000;

struct GcsLinkConfig {
  uint8_t local_id = 0;            // this end: a UAV (0-254) or the GCS (kGcsId)
  double period_s = 0.1;           // one packet per period (seed: 10 Hz by default)
  size_t max_packet_bytes = 1400;  // below a typical path MTU
  size_t max_payload_bytes = 1024;
  size_t max_queued_messages = 4096;
};

enum class GcsLinkStatus {
  kOk,
  kPayloadTooLarge,  // over max_payload_bytes (or too large for one packet)
  kQueueFull,        // max_queued_messages unacknowledged
  kMalformed,        // a packet that does not parse (ignored)
  kIo,               // a socket call failed
};
const char* gcs_link_status_name(GcsLinkStatus s);

struct GcsMessage {
  uint16_t topic = 0;
  uint8_t from = 0;  // the sender's id
  uint32_t id = 0;   // the sender's message number
  std::vector<uint8_t> payload;
};

struct GcsLinkStats {
  uint64_t packets_sent = 0;
  uint64_t packets_received = 0;
  uint64_t packets_malformed = 0;
  uint64_t messages_published = 0;
  uint64_t messages_superseded = 0;  // latest-only messages replaced before they were acknowledged
  uint64_t messages_acked = 0;
  uint64_t retransmissions = 0;    // message records sent again
  uint64_t messages_received = 0;  // delivered to take_received()
  uint64_t duplicates = 0;         // received again (our ack was lost) and not delivered twice
};

class GcsLinkCore {
 public:
  explicit GcsLinkCore(const GcsLinkConfig& config);
  ~GcsLinkCore();
  GcsLinkCore(GcsLinkCore&&) noexcept;
  GcsLinkCore& operator=(GcsLinkCore&&) noexcept;

  // Queues a message for the peer (a latest-only topic replaces its pending message).
  // kPayloadTooLarge or kQueueFull otherwise. Not thread-safe: one thread owns a core.
  GcsLinkStatus publish(uint16_t topic, const std::vector<uint8_t>& payload);
  // Handles a packet received at local time now_us: acknowledgements, new messages, the clock
  // offset. kMalformed (nothing applied) for a packet that does not parse.
  GcsLinkStatus on_packet(const uint8_t* data, size_t size, int64_t now_us);
  // The packet to send now, once per period (the first call sends at once); nullopt between
  // periods.
  std::optional<std::vector<uint8_t>> poll(int64_t now_us);
  // Local time at which poll() next returns a packet.
  int64_t next_poll_us() const;
  // The messages received since the last call, in arrival order, each once.
  std::vector<GcsMessage> take_received();

  // Algorithm 6: local clock - GCS clock, in us; nullopt before the first packet from the GCS (and
  // on the GCS itself).
  std::optional<int64_t> clock_offset_us() const;
  std::optional<int64_t> to_gcs_time_us(int64_t local_us) const;
  std::optional<int64_t> to_local_time_us(int64_t gcs_us) const;

  size_t pending() const;                // messages not yet acknowledged
  size_t pending(uint16_t topic) const;  // of one topic
  const GcsLinkStats& stats() const;
  const GcsLinkConfig& config() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// Where a GcsLink's socket binds and where it sends. remote_port 0: learn the peer from the first
// packet received (a ground station on a public address that UAVs call).
struct GcsLinkEndpoint {
  std::string bind_address = "0.0.0.0";
  uint16_t bind_port = 0;  // 0: ephemeral
  std::string remote_host = "127.0.0.1";
  uint16_t remote_port = 0;
};

// The UDP adapter: one non-blocking socket and a core. Drive it from an event loop — watch fd() for
// input and call service() then, and at next_service_us() — or call service() from any periodic
// loop. Not thread-safe: one thread owns a link.
class GcsLink {
 public:
  // Opens and binds the socket. Null (and *error naming the address) if that fails.
  static std::unique_ptr<GcsLink> open(const GcsLinkConfig& config, const GcsLinkEndpoint& endpoint,
                                       std::string* error);
  ~GcsLink();
  GcsLink(const GcsLink&) = delete;
  GcsLink& operator=(const GcsLink&) = delete;

  int fd() const;
  uint16_t local_port() const;

  // As GcsLinkCore::publish.
  GcsLinkStatus publish(uint16_t topic, const std::vector<uint8_t>& payload);
  // Reads every datagram waiting (never blocks) into the core, then sends the period's packet if
  // one is due at now_us. kIo if the send failed (the packet counts as lost; the protocol
  // retransmits).
  GcsLinkStatus service(int64_t now_us);
  int64_t next_service_us() const;
  std::vector<GcsMessage> take_received();

  GcsLinkCore& core();
  const GcsLinkCore& core() const;

 private:
  struct Impl;
  explicit GcsLink(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

// A ground station's ends of `count` links (one per UAV) on loopback ephemeral ports, each
// learning its UAV's address from the first packet (the UAVs call the station). Empty, with
// *error naming the address, if one cannot be opened.
std::vector<std::unique_ptr<GcsLink>> open_station_links(int count, const GcsLinkConfig& config,
                                                         std::string* error);

}  // namespace uavsim::client
