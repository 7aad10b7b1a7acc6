// ParamClient against a scripted vehicle on a fake link: reads and writes by name, the type kept
// from the vehicle's last report, a value the vehicle refuses, and an unknown name.
#include "param_client.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <map>

#include "fake_mav_port.hpp"
#include "uavsim/common/mavlink/generated/enums.hpp"
#include "uavsim/common/mavlink/wire.hpp"

namespace uavsim::client {
namespace {

namespace mav = common::mavlink;
namespace msg = common::mavlink::msg;
using mav::to_underlying;
using testing::as;
using testing::FakeMavPort;

constexpr double kTimeoutS = 5.0;
constexpr std::uint8_t kInt32 = to_underlying(mav::MavParamType::Int32);

class ParamClientTest : public ::testing::Test {
 protected:
  ParamClientTest() {
    // a vehicle with two parameters; WPNAV_SPEED is capped at 2000
    port_.vehicle = [this](const FakeMavPort::Sent& s) {
      if (auto r = as<msg::ParamRequestRead>(s)) answer(std::string(mav::get_string(r->param_id)));
      if (auto p = as<msg::ParamSet>(s)) {
        const std::string name(mav::get_string(p->param_id));
        if (!params_.count(name)) return;
        params_[name] = name == "WPNAV_SPEED" ? std::min(p->param_value, 2000.0f) : p->param_value;
        answer(name);
      }
    };
  }
  void answer(const std::string& name) {
    if (!params_.count(name)) return;  // ArduPilot ignores an unknown name
    msg::ParamValue v;
    mav::set_string(v.param_id, name);
    v.param_value = params_[name];
    v.param_type = name == "FS_GCS_ENABLE" ? kInt32 : to_underlying(mav::MavParamType::Real32);
    port_.reply(v);
  }

  std::unique_ptr<EventLoop> loop_ = testing::make_loop();
  FakeMavPort port_{*loop_};
  ParamClient params_client_{*loop_, port_};
  std::map<std::string, float> params_{{"FS_GCS_ENABLE", 1.0f}, {"WPNAV_SPEED", 500.0f}};
};

TEST_F(ParamClientTest, GetAsksByNameAndReturnsTheValue) {
  auto v = params_client_.get("WPNAV_SPEED", kTimeoutS);
  ASSERT_TRUE(v) << v.message();
  EXPECT_EQ(*v, 500.0f);
  const auto sent = port_.sent<msg::ParamRequestRead>();
  ASSERT_EQ(sent.size(), 1u);
  EXPECT_EQ(sent[0].param_index, -1);  // by name
  EXPECT_EQ(mav::get_string(sent[0].param_id), "WPNAV_SPEED");
}

TEST_F(ParamClientTest, SetSendsTheTypeTheVehicleReportedAndReturnsItsEcho) {
  ASSERT_TRUE(params_client_.get("FS_GCS_ENABLE", kTimeoutS));
  auto v = params_client_.set("FS_GCS_ENABLE", 2.0f, kTimeoutS);
  ASSERT_TRUE(v) << v.message();
  EXPECT_EQ(*v, 2.0f);
  const auto sent = port_.sent<msg::ParamSet>();
  ASSERT_EQ(sent.size(), 1u);
  EXPECT_EQ(sent[0].param_type, kInt32);
  // never read before: REAL32
  ASSERT_TRUE(params_client_.set("WPNAV_SPEED", 800.0f, kTimeoutS));
  EXPECT_EQ(port_.sent<msg::ParamSet>().back().param_type,
            to_underlying(mav::MavParamType::Real32));
}

TEST_F(ParamClientTest, AValueTheVehicleKeptIsDenied) {
  auto v = params_client_.set("WPNAV_SPEED", 5000.0f, kTimeoutS);
  ASSERT_FALSE(v);
  EXPECT_EQ(v.code(), Error::kDenied);
  EXPECT_EQ(v.message(), "set WPNAV_SPEED = 5000: the vehicle kept 2000");
}

TEST_F(ParamClientTest, AnUnknownNameIsATimeoutNamingIt) {
  auto v = params_client_.get("NO_SUCH_PARAM", 0.05);
  ASSERT_FALSE(v);
  EXPECT_EQ(v.code(), Error::kTimeout);
  EXPECT_NE(v.message().find("no PARAM_VALUE for NO_SUCH_PARAM"), std::string::npos) << v.message();
}

TEST_F(ParamClientTest, BadNamesValuesAndNoLinkFailAtOnce) {
  EXPECT_EQ(params_client_.get("", kTimeoutS).code(), Error::kInvalidArgument);
  EXPECT_EQ(params_client_.get("SEVENTEEN_CHARS_X", kTimeoutS).code(), Error::kInvalidArgument);
  EXPECT_EQ(params_client_.set("WPNAV_SPEED", std::nanf(""), kTimeoutS).code(),
            Error::kInvalidArgument);
  port_.open = false;
  EXPECT_EQ(params_client_.get("WPNAV_SPEED", kTimeoutS).code(), Error::kNotConnected);
  EXPECT_EQ(port_.sent_count(), 0u);
}

}  // namespace
}  // namespace uavsim::client
