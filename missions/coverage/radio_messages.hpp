// The flock's radio messages in 802.15.4 frames of at most 127 bytes (the thesis the project
// descends from, sections 3.3, 3.4 and 6.2), or fewer where the channel says so: a channel that
// accounts for the MAC header carries at most 116 (uavsim::client::A2aRadio::max_frame_bytes()),
// and the encoders fit every frame to the size they are given (FrameFit). On a channel of larger
// frames (802.11: 1500 bytes) aggregation fragments grow to its size; beacons stay as on 127.
// Little-endian, fixed point:
//
//   beacon (8 per second, section 3.3), 14 + 14 * n bytes, n <= 8 and within the frame size (8 in
//   127 bytes, 7 in 116):
//     u8 type = 1 | u8 sender | u8 flags | u16 seq | i16 x_dm | i16 y_dm |
//     u16 heading (2 pi / 65536) | i8 vx (0.1 m/s) | i8 vy | u8 n | n records:
//       u8 id | u16 seq | i16 x_dm | i16 y_dm | u16 heading | i8 vx | i8 vy | u8 hops | u16 age_ms
//   flags: bit 0 going home, bit 1 the sender has landed, bits 2-4 the survey round (mod 8; a
//   recall after a loss on the way home starts the next one, see agent.hpp), bit 5 the sender is
//   homebound (in Going Home, of whichever round: flying home or landing). A record's hops byte
//   carries that agent's landed flag in bit 7.
//   A full ADB of 25 agents does not fit one frame; each beacon carries the next n records of the
//   ADB in turn (a rotating window), so a full copy crosses every hop in ceil(size / n) beacons.
//   Algorithm 1 merges record by record, so a partial copy is merged exactly like a full one; the
//   allowed ages (Algorithm 2) are set to cover the rotation.
//
//   aggregation fragment (section 3.4), 29 bytes + runs:
//     u8 type = 2 | u8 sender | u8 origin | u16 query_id | u16 version | u8 fragment | u8 fragments
//     | u64 responded | u64 acked | u16 first_stripe | u16 stripe_count | runs:
//       u8 repeat | u8 n | n * (u16 start_dm | u16 end_dm)
//   A run is one stripe's interval list repeated for `repeat` consecutive stripes: a flock sweeping
//   along x leaves the same intervals in stripe after stripe, so a whole map is usually a few runs.
//   Interval ends are rounded inwards to 0.1 m (never claiming more than was covered). A map that
//   does not fit one frame is cut into fragments by stripe ranges; a receiver uses a message once
//   it has every fragment of the same (sender, origin, query, version).
//
// Positions are relative to the area origin, so any rectangle up to 3000 m fits 16 bits.
#pragma once

#include <bitset>
#include <cstdint>
#include <optional>
#include <string>
#include <tuple>
#include <vector>

#include "agents_database.hpp"
#include "aggregation.hpp"

namespace uavsim::missions::coverage {

// The largest beacon of the layout: 802.15.4's 127-byte PHY payload.
inline constexpr size_t kMaxFrameBytes = 127;
// The largest aggregation fragment: 802.11's 1500 bytes. Beacons stay within 127 bytes (8
// records) on any channel; a map sent in fewer, larger fragments arrives whole more often where
// broadcasts are lost (a message is used once every fragment of it has arrived).
inline constexpr size_t kMaxAggregateFrameBytes = 1500;
// The most ADB records a beacon carries (8 in a 127-byte frame, as the thesis's flock sent).
inline constexpr int kMaxRecordsPerBeacon = 8;
// The smallest frame the flock can talk in: an aggregation fragment's header (29 bytes) and one
// stripe's run of one interval (6). A beacon with one record (28 bytes) fits too.
inline constexpr size_t kMinFrameBytes = 35;

using Frame = std::vector<uint8_t>;

// The flock's frames fitted to a channel: the largest frame its encoders write, and the ADB
// records a beacon carries.
struct FrameFit {
  size_t max_frame_bytes = kMaxFrameBytes;
  int beacon_records = kMaxRecordsPerBeacon;
};

// The fit for a channel whose frames carry at most channel_max_bytes: aggregation fragments of up
// to kMaxAggregateFrameBytes of them, beacons of up to kMaxFrameBytes with as many records as fit,
// at most kMaxRecordsPerBeacon. Nothing, with the reason in *error, when
// channel_max_bytes is under kMinFrameBytes.
std::optional<FrameFit> fit_frames(size_t channel_max_bytes, std::string* error);

enum class MessageType : uint8_t { kBeacon = 1, kAggregate = 2 };

// Survey rounds are counted modulo this (3 bits of the beacon's flags); see agent.hpp.
inline constexpr int kRounds = 8;

struct Beacon {
  AgentRecord self;  // id, seq, x, y, heading, velocity, landed (hops and age unused)
  bool going_home = false;
  uint8_t round = 0;                 // [0, kRounds)
  bool homebound = false;            // the sender is in Going Home (flying home or landing)
  std::vector<AgentRecord> records;  // at most FrameFit::beacon_records
};

// Positions are sent relative to (origin_x_m, origin_y_m).
struct RadioFrameOrigin {
  double x_m = 0.0;
  double y_m = 0.0;
};

// The beacon with its first fit.beacon_records records (the rest are not sent), at most
// fit.max_frame_bytes long. fit comes from fit_frames().
Frame encode_beacon(const Beacon& b, const RadioFrameOrigin& origin, const FrameFit& fit);
// A beacon of any fit (up to kMaxFrameBytes); nothing when the frame is malformed.
std::optional<Beacon> decode_beacon(const Frame& f, const RadioFrameOrigin& origin);
// The same into *out, reusing its records' memory (every agent decodes every beacon it hears);
// false when the frame is malformed (*out then holds nothing of use).
bool decode_beacon(const Frame& f, const RadioFrameOrigin& origin, Beacon* out);

// One message as one or more frames, each at most fit.max_frame_bytes long (at most
// (fit.max_frame_bytes - 31) / 4 intervals a stripe are sent, at most 255: 24 in 127 bytes, 21 in
// 116; the rest dropped, so a message claims less, never more). fit comes from fit_frames().
std::vector<Frame> encode_aggregate(const AggregateMessage& m, const FrameFit& fit);

// The first byte of a frame, if it is one of ours.
std::optional<MessageType> message_type(const Frame& f);

// The runs of one aggregation fragment (or of a station map), decoded: every run's intervals in
// one flat list. The reassembler keeps one between fragments, so that decoding allocates nothing
// once warm (every agent decodes every aggregation fragment it hears).
struct DecodedRuns {
  struct Span {
    int first = 0;   // stripe
    int repeat = 0;  // stripes first .. first+repeat-1 share the intervals
    size_t begin = 0;
    size_t count = 0;
  };
  std::vector<Span> spans;
  std::vector<Interval> intervals;

  void clear() {
    spans.clear();
    intervals.clear();
  }
  // Sets the stripes of every run (AreaParts::set_stripes).
  void apply_to(AreaParts* apd) const;
};

// Collects aggregation fragments; hands out a message when its last missing fragment arrives.
// Malformed fragments are ignored. Keeps at most one message in progress per sender, each in
// memory that the next message of that sender reuses.
class AggregateReassembler {
 public:
  explicit AggregateReassembler(int stripes) : stripes_(stripes) {}
  // The message this fragment completes, if any: valid until the next add() (the fragments of
  // the sender's next message are gathered into the same memory).
  const AggregateMessage* add(const Frame& f);

 private:
  struct Partial {
    int origin = 0;
    uint16_t query_id = 0;
    uint16_t version = 0;
    int fragments = 0;          // 0: nothing in progress (the next fragment starts a message)
    std::bitset<256> received;  // bit per fragment (<= 255 fragments)
    int received_count = 0;     // bits set in received
    AggregateMessage message;
  };
  int stripes_;
  std::vector<Partial> partial_;  // by sender id, grown on demand
  DecodedRuns runs_;              // the fragment being read
};

// An APD as one byte string, for the ground-station link (3.6), where a message is not limited to
// a radio frame: u16 stripe_count | the runs of the aggregation fragment for every stripe (at most
// 255 intervals a stripe are sent; ends rounded inwards to 0.1 m, so it never claims more).
std::vector<uint8_t> encode_apd(const AreaParts& apd);
// Bytes as encode_apd writes them for a rectangle of `stripes` stripes; nothing when they are
// malformed or name another stripe count.
std::optional<AreaParts> decode_apd(const std::vector<uint8_t>& bytes, int stripes);

}  // namespace uavsim::missions::coverage
