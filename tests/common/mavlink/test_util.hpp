// Helpers shared by the MAVLink codec tests: hex, the reference vectors, and re-encoding any frame.
#pragma once

#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <tuple>
#include <vector>

#include "uavsim/common/mavlink/codec.hpp"
#include "uavsim/common/mavlink/generated/messages.hpp"

namespace uavsim::common::mavlink::test {

inline std::vector<std::uint8_t> from_hex(const std::string& hex) {
  std::vector<std::uint8_t> out;
  for (std::size_t i = 0; i + 1 < hex.size(); i += 2) {
    out.push_back(static_cast<std::uint8_t>(std::stoi(hex.substr(i, 2), nullptr, 16)));
  }
  return out;
}

inline std::string to_hex(std::span<const std::uint8_t> bytes) {
  static const char* kDigits = "0123456789abcdef";
  std::string s;
  for (std::uint8_t b : bytes) {
    s += kDigits[b >> 4];
    s += kDigits[b & 15];
  }
  return s;
}

inline std::string data_path(const std::string& name) {
  return std::string(UAVSIM_MAVLINK_TEST_DATA_DIR) + "/" + name;
}

struct Vector {
  std::string label;
  std::vector<std::uint8_t> bytes;
};

// tests/data/mavlink/test_vectors.txt: "label hexframe" lines, '#' comments
inline std::vector<Vector> load_vectors() {
  std::ifstream in(data_path("test_vectors.txt"));
  if (!in) throw std::runtime_error("cannot open " + data_path("test_vectors.txt"));
  std::vector<Vector> out;
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    // the hex frame is the last word; labels may contain spaces
    const std::size_t split = line.find_last_of(' ');
    if (split == std::string::npos) continue;
    Vector v;
    v.label = line.substr(0, split);
    v.bytes = from_hex(line.substr(split + 1));
    out.push_back(std::move(v));
  }
  return out;
}

// The signing key of the signed reference frame: bytes 0..31.
inline SecretKey reference_key() {
  SecretKey key;
  for (std::size_t i = 0; i < key.size(); ++i) key[i] = static_cast<std::uint8_t>(i);
  return key;
}

// Decodes a frame with its generated struct and encodes it again with the frame's own header (and
// signature parameters, given the key). Empty when no struct is generated for the id.
inline EncodedFrame reencode(const Frame& frame, const SecretKey& key = reference_key()) {
  FrameHeader h;
  h.sysid = frame.sysid;
  h.compid = frame.compid;
  h.seq = frame.seq;
  h.version = frame.version;
  if (frame.signature)
    h.signing = SigningParams{key, frame.signature->link_id, frame.signature->timestamp_10us};
  EncodedFrame out;
  std::apply(
      [&](auto... tag) {
        ((frame.msgid == decltype(tag)::kId
              ? (out = encode(h, decltype(tag)::decode(frame.payload.data())), 0)
              : 0),
         ...);
      },
      msg::AllMessages{});
  return out;
}

}  // namespace uavsim::common::mavlink::test
