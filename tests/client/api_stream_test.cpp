// The client's reader of the sim API's stream (client_cpp/src/api_stream.hpp): lines, frames that
// follow their header, bytes split anywhere, and the limits that keep a bad peer from making the
// client buffer without bound.
#include "api_stream.hpp"

#include <gtest/gtest.h>

#include <string>
#include <vector>

namespace uavsim::client {
namespace {

struct Seen {
  std::vector<nlohmann::json> messages;
  std::vector<std::string> payloads;
};

void feed(ApiStream& s, const std::string& bytes, Seen* seen) {
  s.feed(bytes.data(), bytes.size(), [seen](const nlohmann::json& j, std::string_view payload) {
    seen->messages.push_back(j);
    seen->payloads.emplace_back(payload);
  });
}

TEST(ApiStream, LinesAndAFrameSplitAnywhere) {
  const std::string bytes =
      "{\"event\":\"tick\",\"tick\":1}\n{\"event\":\"frame\",\"bytes\":5}\nABCDE{\"id\":2}\nnot "
      "json\n";
  ApiStream s;
  Seen seen;
  for (char c : bytes) feed(s, std::string(1, c), &seen);  // one byte at a time
  ASSERT_EQ(seen.messages.size(), 4u);
  EXPECT_EQ(seen.messages[0]["tick"], 1);
  EXPECT_EQ(seen.messages[1]["event"], "frame");
  EXPECT_EQ(seen.payloads[1], "ABCDE");
  EXPECT_EQ(seen.messages[2]["id"], 2);
  EXPECT_TRUE(seen.messages[3].is_discarded());  // malformed lines are passed on as discarded
  EXPECT_FALSE(s.error());
}

TEST(ApiStream, ALineWithoutEndOverTheLimitStopsTheStream) {
  ApiStream s(64, 1024);
  Seen seen;
  feed(s, "{\"id\":1}\n", &seen);
  feed(s, std::string(65, 'x'), &seen);  // no newline, already over 64 bytes
  ASSERT_TRUE(s.error());
  EXPECT_NE(s.error()->find("line longer than 64"), std::string::npos) << *s.error();
  feed(s, "\n{\"id\":2}\n", &seen);  // nothing more is taken
  EXPECT_EQ(seen.messages.size(), 1u);
}

TEST(ApiStream, AFrameOverTheLimitStopsTheStreamBeforeItsBytesArrive) {
  ApiStream s(1024, 100);
  Seen seen;
  feed(s, "{\"event\":\"frame\",\"bytes\":100}\n", &seen);
  feed(s, std::string(100, 'p'), &seen);
  ASSERT_EQ(seen.payloads.size(), 1u);  // exactly the limit is fine
  feed(s, "{\"event\":\"frame\",\"bytes\":4294967296}\n", &seen);
  ASSERT_TRUE(s.error());
  EXPECT_EQ(*s.error(), "sim API: a frame header without a usable `bytes` (at most 100)");
  EXPECT_EQ(seen.messages.size(), 1u);
}

TEST(ApiStream, AFrameHeaderWithAWrongTypeIsAnErrorNotAnExceptionAndAnEmptyFrameIsOne) {
  ApiStream s;
  Seen seen;
  feed(s, "{\"event\":\"frame\",\"bytes\":0,\"seq\":7}\n{\"id\":1}\n", &seen);
  ASSERT_EQ(seen.messages.size(), 2u);
  EXPECT_EQ(seen.messages[0]["seq"], 7);
  EXPECT_EQ(seen.payloads[0], "");
  feed(s, "{\"event\":\"frame\",\"bytes\":\"many\"}\n", &seen);
  ASSERT_TRUE(s.error());
  EXPECT_EQ(seen.messages.size(), 2u);
  ApiStream t;
  Seen other;
  feed(t, "{\"event\":5}\n", &other);  // an event that is not a string is an ordinary message
  EXPECT_EQ(other.messages.size(), 1u);
  EXPECT_FALSE(t.error());
}

}  // namespace
}  // namespace uavsim::client
