// The request ring's binary records (common/shm_requests.hpp): what is encoded decodes to the same
// fields, and whatever a client writes that breaks the layout or a range is refused by name.
#include "uavsim/common/shm_requests.hpp"

#include <gtest/gtest.h>

#include <cstring>
#include <limits>

#include "uavsim/common/shm_ring.hpp"

namespace uavsim::common::shm {
namespace {

std::vector<std::uint8_t> a_frame(std::int32_t to = 4) {
  std::vector<std::uint8_t> out;
  const std::uint8_t data[] = {1, 2, 3, 250};
  encode_radio_send(7, 3, to, data, &out);
  return out;
}

DoneRecord a_done() {
  DoneRecord d;
  d.tag = 0;
  d.quiet = true;
  d.tick = 41;
  d.busy_until_s = 2.25;
  d.mavlink_seq = {{0, 255}, {12, 3}};
  return d;
}

TEST(ShmRequestRecords, ARadioSendRoundTripsEveryField) {
  for (const std::int32_t to : {4, -1}) {
    std::string why;
    const auto r = decode_radio_send(a_frame(to), &why);
    ASSERT_TRUE(r) << why;
    EXPECT_EQ(r->tag, 7u);
    EXPECT_EQ(r->vehicle, 3u);
    EXPECT_EQ(r->to, to);
    EXPECT_EQ(r->data, (std::vector<std::uint8_t>{1, 2, 3, 250}));
  }
}

TEST(ShmRequestRecords, ADoneRoundTripsEveryFieldAndItsAbsentOnes) {
  std::vector<std::uint8_t> bytes;
  encode_done(a_done(), &bytes);
  std::string why;
  auto d = decode_done(bytes, &why);
  ASSERT_TRUE(d) << why;
  EXPECT_TRUE(d->quiet);
  EXPECT_EQ(d->tick, 41);
  EXPECT_EQ(d->busy_until_s, 2.25);
  EXPECT_EQ(d->mavlink_seq, a_done().mavlink_seq);

  bytes.clear();
  encode_done(DoneRecord{}, &bytes);
  d = decode_done(bytes, &why);
  ASSERT_TRUE(d) << why;
  EXPECT_FALSE(d->quiet);
  EXPECT_FALSE(d->tick);
  EXPECT_FALSE(d->busy_until_s);
  EXPECT_TRUE(d->mavlink_seq.empty());
}

TEST(ShmRequestRecords, EveryCutOrAddedByteIsRefused) {
  std::vector<std::uint8_t> send = a_frame(), done;
  encode_done(a_done(), &done);
  std::string why;
  for (std::size_t n = 0; n < send.size(); ++n) {
    EXPECT_FALSE(decode_radio_send(std::span(send).first(n), &why)) << n;
  }
  for (std::size_t n = 0; n < done.size(); ++n) {
    EXPECT_FALSE(decode_done(std::span(done).first(n), &why)) << n;
  }
  send.push_back(0);
  done.push_back(0);
  EXPECT_FALSE(decode_radio_send(send, &why));
  EXPECT_FALSE(decode_done(done, &why));
  EXPECT_NE(why.find("after a done record"), std::string::npos) << why;
}

// the byte offsets of the layouts in shm_requests.hpp
constexpr std::size_t kSendVehicle = 4, kSendTo = 8, kSendLength = 12;
constexpr std::size_t kDoneFlags = 4, kDoneBusy = 13, kDoneCount = 21, kDoneFirstVehicle = 25;

template <typename T>
std::vector<std::uint8_t> patched(std::vector<std::uint8_t> bytes, std::size_t at, T value) {
  std::memcpy(bytes.data() + at, &value, sizeof(T));
  return bytes;
}

TEST(ShmRequestRecords, FieldsOutOfRangeAreRefused) {
  const std::vector<std::uint8_t> send = a_frame();
  std::vector<std::uint8_t> done;
  encode_done(a_done(), &done);
  std::string why;
  EXPECT_FALSE(decode_radio_send(patched(send, kSendVehicle, kMaxVehicleIndex), &why));
  EXPECT_FALSE(decode_radio_send(patched(send, kSendTo, std::int32_t{-2}), &why));
  EXPECT_FALSE(
      decode_radio_send(patched(send, kSendTo, static_cast<std::int32_t>(kMaxVehicleIndex)), &why));
  EXPECT_FALSE(decode_radio_send(patched(send, kSendLength, std::uint16_t{0}), &why));
  EXPECT_FALSE(decode_radio_send(
      patched(send, kSendLength, static_cast<std::uint16_t>(kMaxRadioFrameBytes + 1)), &why));
  EXPECT_NE(why.find("out of range"), std::string::npos) << why;

  EXPECT_FALSE(decode_done(patched(done, kDoneFlags, std::uint8_t{8}), &why));
  EXPECT_FALSE(
      decode_done(patched(done, kDoneBusy, std::numeric_limits<double>::infinity()), &why));
  EXPECT_FALSE(
      decode_done(patched(done, kDoneBusy, std::numeric_limits<double>::quiet_NaN()), &why));
  EXPECT_FALSE(decode_done(patched(done, kDoneCount, std::uint32_t{0xFFFFFFFF}), &why));
  EXPECT_NE(why.find("announcing"), std::string::npos) << why;
  EXPECT_FALSE(decode_done(patched(done, kDoneFirstVehicle, kMaxVehicleIndex), &why));
  // without the busy_until flag its bytes are not a time and not looked at
  DoneRecord no_busy = a_done();
  no_busy.busy_until_s.reset();
  std::vector<std::uint8_t> bytes;
  encode_done(no_busy, &bytes);
  EXPECT_TRUE(decode_done(patched(bytes, kDoneBusy, std::numeric_limits<double>::infinity()), &why))
      << why;
}

}  // namespace
}  // namespace uavsim::common::shm
