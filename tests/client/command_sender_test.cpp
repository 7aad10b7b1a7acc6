// CommandSender against a fake link: the ACK paths (accepted, refused, in progress), the retry on
// silence and its timeout, and the non-blocking form's contract (done posted, replaced, link lost).
#include "command_sender.hpp"

#include <gtest/gtest.h>

#include <optional>

#include "fake_mav_port.hpp"

namespace uavsim::client {
namespace {

namespace mav = common::mavlink;
namespace msg = common::mavlink::msg;
using mav::MavCmd;
using mav::MavResult;
using testing::as;
using testing::FakeMavPort;

// short attempts: a silent vehicle costs 3 x 20 ms of loop time
constexpr double kAttemptS = 0.02;
constexpr int kAttempts = 3;

msg::CommandAck ack(std::uint16_t command, MavResult result, std::uint8_t gcs_sysid = 255) {
  msg::CommandAck a;
  a.command = command;
  a.result = static_cast<std::uint8_t>(mav::to_underlying(result));
  a.target_system = gcs_sysid;
  return a;
}

constexpr std::uint16_t id(MavCmd c) { return static_cast<std::uint16_t>(mav::to_underlying(c)); }

class CommandSenderTest : public ::testing::Test {
 protected:
  CommandSenderTest() {
    config_.command_timeout_s = kAttemptS;
    config_.command_attempts = kAttempts;
  }
  // the vehicle answers every COMMAND_LONG whose attempt (confirmation) is `on_attempt` with result
  void answer(MavResult result, int on_attempt = 0) {
    port_.vehicle = [this, result, on_attempt](const FakeMavPort::Sent& s) {
      if (auto c = as<msg::CommandLong>(s); c && c->confirmation == on_attempt) {
        port_.reply(ack(c->command, result));
      }
    };
  }

  std::unique_ptr<EventLoop> loop_ = testing::make_loop();
  FakeMavPort port_{*loop_};
  VehicleConfig config_;
  CommandSender sender_{*loop_, port_, config_};
};

TEST_F(CommandSenderTest, AnAcceptedAckEndsTheBlockingCallAfterOneCommand) {
  answer(MavResult::Accepted);
  auto r = sender_.send(MavCmd::NavTakeoff, {0, 0, 0, 0, 0, 0, 10.0f});
  ASSERT_TRUE(r) << r.message();
  const auto sent = port_.sent<msg::CommandLong>();
  ASSERT_EQ(sent.size(), 1u);
  EXPECT_EQ(sent[0].command, id(MavCmd::NavTakeoff));
  EXPECT_EQ(sent[0].confirmation, 0);
  EXPECT_EQ(sent[0].param7, 10.0f);
  EXPECT_EQ(sent[0].target_system, port_.sysid);
}

TEST_F(CommandSenderTest, ARefusalCarriesTheMavResultAndItsName) {
  answer(MavResult::Denied);
  auto r = sender_.send(MavCmd::ComponentArmDisarm, {1, 0, 0, 0, 0, 0, 0});
  ASSERT_FALSE(r);
  EXPECT_EQ(r.code(), Error::kDenied);
  EXPECT_EQ(r.error().mav_result, 2);
  EXPECT_EQ(r.message(), "COMPONENT_ARM_DISARM refused by the vehicle: MAV_RESULT_DENIED (2)");

  answer(MavResult::TemporarilyRejected);
  EXPECT_EQ(sender_.send(MavCmd::ComponentArmDisarm, {}).code(), Error::kTemporarilyRejected);
  answer(MavResult::Failed);
  EXPECT_EQ(sender_.send(MavCmd::ComponentArmDisarm, {}).code(), Error::kFailed);
  answer(MavResult::Unsupported);
  EXPECT_EQ(sender_.send(MavCmd::ComponentArmDisarm, {}).code(), Error::kUnsupported);
}

TEST_F(CommandSenderTest, SilenceIsRetriedWithTheAttemptNumberThenTimesOut) {
  auto r = sender_.send(MavCmd::NavLand, {});
  ASSERT_FALSE(r);
  EXPECT_EQ(r.code(), Error::kTimeout);
  EXPECT_NE(r.message().find("no COMMAND_ACK for NAV_LAND after 3 attempt(s)"), std::string::npos)
      << r.message();
  const auto sent = port_.sent<msg::CommandLong>();
  ASSERT_EQ(sent.size(), static_cast<std::size_t>(kAttempts));
  for (int i = 0; i < kAttempts; ++i) EXPECT_EQ(sent[i].confirmation, i);
}

TEST_F(CommandSenderTest, AnAnswerToARetryEndsTheCommand) {
  answer(MavResult::Accepted, /*on_attempt=*/1);
  ASSERT_TRUE(sender_.send(MavCmd::NavLand, {}));
  EXPECT_EQ(port_.sent<msg::CommandLong>().size(), 2u);
}

TEST_F(CommandSenderTest, InProgressWaitsForTheFinalAckWithoutResending) {
  port_.vehicle = [this](const FakeMavPort::Sent& s) {
    if (auto c = as<msg::CommandLong>(s)) {
      port_.reply(ack(c->command, MavResult::InProgress));
      // the final answer half an attempt later: before the (re-armed) retry would fire
      loop_->call_after(kAttemptS / 2,
                        [this, c] { port_.deliver(ack(c->command, MavResult::Accepted)); });
    }
  };
  ASSERT_TRUE(sender_.send(MavCmd::NavTakeoff, {}));
  EXPECT_EQ(port_.sent<msg::CommandLong>().size(), 1u);
}

TEST_F(CommandSenderTest, AnAckForAnotherGroundStationIsIgnored) {
  port_.vehicle = [this](const FakeMavPort::Sent& s) {
    if (auto c = as<msg::CommandLong>(s)) {
      // attempt 0 is answered to GCS 42 only; attempt 1 to us
      port_.reply(ack(c->command, MavResult::Accepted, c->confirmation == 0 ? 42 : 255));
    }
  };
  ASSERT_TRUE(sender_.send(MavCmd::NavLand, {}));
  EXPECT_EQ(port_.sent<msg::CommandLong>().size(), 2u);
}

TEST_F(CommandSenderTest, TheAsyncDoneRunsOnTheLoopNeverInsideTheCall) {
  answer(MavResult::Accepted);
  std::optional<Result<void>> got;
  sender_.send_async(id(MavCmd::NavLand), {}, [&](Result<void> r) { got = r; });
  EXPECT_FALSE(got.has_value());
  ASSERT_TRUE(loop_->run_until([&] { return got.has_value(); }, 1.0));
  EXPECT_TRUE(*got);
}

TEST_F(CommandSenderTest, ANewerCommandWithTheSameIdCancelsTheFirst) {
  std::optional<Result<void>> first, second;
  sender_.send_async(id(MavCmd::NavLand), {}, [&](Result<void> r) { first = r; });
  answer(MavResult::Accepted);
  sender_.send_async(id(MavCmd::NavLand), {}, [&](Result<void> r) { second = r; });
  ASSERT_TRUE(loop_->run_until([&] { return first && second; }, 1.0));
  EXPECT_EQ(first->code(), Error::kCancelled);
  EXPECT_TRUE(*second);
}

TEST_F(CommandSenderTest, ALostLinkEndsEveryPendingCommand) {
  std::optional<Result<void>> land, takeoff;
  sender_.send_async(id(MavCmd::NavLand), {}, [&](Result<void> r) { land = r; });
  sender_.send_async(id(MavCmd::NavTakeoff), {}, [&](Result<void> r) { takeoff = r; });
  sender_.fail_all("the link was lost: reset by peer");
  ASSERT_TRUE(loop_->run_until([&] { return land && takeoff; }, 1.0));
  EXPECT_EQ(land->code(), Error::kConnectionLost);
  EXPECT_EQ(land->message(), "NAV_LAND: the link was lost: reset by peer");
  EXPECT_EQ(takeoff->code(), Error::kConnectionLost);
}

TEST_F(CommandSenderTest, DroppedCommandsNeverCallTheirDone) {
  bool called = false;
  sender_.send_async(id(MavCmd::NavLand), {}, [&](Result<void>) { called = true; });
  sender_.drop_all();
  ASSERT_TRUE(loop_->run_for(kAttemptS * (kAttempts + 1)));
  EXPECT_FALSE(called);
  EXPECT_EQ(port_.sent<msg::CommandLong>().size(), 1u);  // and no retry
}

TEST_F(CommandSenderTest, WithoutALinkBothFormsFailAtOnce) {
  port_.open = false;
  auto r = sender_.send(MavCmd::NavLand, {});
  EXPECT_EQ(r.code(), Error::kNotConnected);
  EXPECT_EQ(r.message(), "not connected to a vehicle (fake:1)");
  std::optional<Result<void>> got;
  sender_.send_async(id(MavCmd::NavLand), {}, [&](Result<void> r2) { got = r2; });
  ASSERT_TRUE(loop_->run_until([&] { return got.has_value(); }, 1.0));
  EXPECT_EQ(got->code(), Error::kNotConnected);
  EXPECT_EQ(port_.sent_count(), 0u);
}

TEST(CommandName, IsTheDialectsNameOrTheNumber) {
  EXPECT_EQ(command_name(400), "COMPONENT_ARM_DISARM");
  EXPECT_EQ(command_name(183), "DO_SET_SERVO");
  EXPECT_EQ(command_name(65000), "MAV_CMD 65000");
}

}  // namespace
}  // namespace uavsim::client
