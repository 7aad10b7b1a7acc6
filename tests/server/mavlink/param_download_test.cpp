// The paced parameter download alone.
#include "mavlink/param_download.hpp"

#include <gtest/gtest.h>

namespace uavsim::server::mavlink {
namespace {

TEST(ParamDownload, SendsTheTableInOrderSixteenAStep) {
  ParamDownload d;
  std::vector<std::size_t> sent;
  const auto send = [&](std::size_t i) { sent.push_back(i); };
  d.take(40, send);
  EXPECT_TRUE(sent.empty());  // nothing asked yet
  d.start();
  // 40 parameters: 16 + 16 + 8 over three steps
  d.take(40, send);
  EXPECT_EQ(sent.size(), 16u);
  d.take(40, send);
  EXPECT_EQ(sent.size(), 32u);
  EXPECT_TRUE(d.active());
  d.take(40, send);
  ASSERT_EQ(sent.size(), 40u);
  EXPECT_FALSE(d.active());
  for (std::size_t i = 0; i < sent.size(); ++i) EXPECT_EQ(sent[i], i);
  // a new request starts over
  d.start();
  sent.clear();
  d.take(40, send);
  EXPECT_EQ(sent.front(), 0u);
}

TEST(ParamDownload, FindsAParameterByName) {
  const std::vector<std::string> names = {"SYSID_THISMAV", "WPNAV_SPEED"};
  EXPECT_EQ(param_index(names, "WPNAV_SPEED"), 1u);
  EXPECT_FALSE(param_index(names, "NO_SUCH").has_value());
}

}  // namespace
}  // namespace uavsim::server::mavlink
