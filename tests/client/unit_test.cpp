// client_cpp without a server: Result, PID, geodesy re-export, the event loop on the host clock.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <thread>
#include <type_traits>

#include "uavsim/client/event_loop.hpp"
#include "uavsim/client/geodesy.hpp"
#include "uavsim/client/pid.hpp"
#include "uavsim/client/result.hpp"
#include "uavsim/client/vehicle.hpp"
#include "uavsim/common/angles.hpp"

namespace uavsim::client {
namespace {

constexpr double kPidTol = 1e-9;
constexpr double kRoundTripTol = 1e-9;  // degrees and metres back from a conversion
constexpr double kYawTol_rad = 1e-12;

TEST(Result, ValueAndFailure) {
  Result<int> a = 3;
  ASSERT_TRUE(a);
  EXPECT_EQ(*a, 3);
  Result<int> b = Result<int>::fail(Error::kDenied, "no", 2);
  ASSERT_FALSE(b);
  EXPECT_EQ(b.code(), Error::kDenied);
  EXPECT_EQ(b.error().mav_result, 2);
  EXPECT_EQ(b.value_or(7), 7);
  Result<void> c = b;  // forwards the failure
  ASSERT_FALSE(c);
  EXPECT_EQ(c.message(), "no");
  EXPECT_STREQ(error_name(Error::kTimeout), "timeout");
  EXPECT_DEATH((void)b.value(), "denied: no");
}

TEST(Pid, ProportionalIntegralDerivativeAndLiveGains) {
  Pid pid({.kp = 2.0});
  EXPECT_DOUBLE_EQ(pid.update(1.0, 0.0, 0.1), 2.0);
  pid.set_gains({.kp = 0.0, .ki = 1.0});
  pid.reset();
  double out = 0;
  for (int i = 0; i < 10; ++i) out = pid.update(1.0, 0.0, 0.1);
  EXPECT_NEAR(out, 1.0, kPidTol);  // integral of 1 over 1 s
  pid.set_gains({.kd = 1.0});
  pid.reset();
  pid.update(0.0, 0.0, 0.1);
  EXPECT_NEAR(pid.update(0.0, 0.5, 0.1), -5.0, kPidTol);  // derivative on measurement
  // saturation and anti-windup
  pid.set_gains({.kp = 1.0, .ki = 10.0, .output_min = -1.0, .output_max = 1.0});
  pid.reset();
  for (int i = 0; i < 100; ++i) out = pid.update(5.0, 0.0, 0.1);
  EXPECT_DOUBLE_EQ(out, 1.0);
  out = pid.update(-0.5, 0.0, 0.1);  // comes back at once: no wound-up integral
  EXPECT_LT(out, 0.0);
  // gains from another thread
  std::thread t([&] { pid.set_gains({.kp = 3.0}); });
  t.join();
  EXPECT_DOUBLE_EQ(pid.gains().kp, 3.0);
}

TEST(Geodesy, IsTheServersImplementation) {
  // the client names common's types: one default origin, converted by the server's own functions
  static_assert(std::is_same_v<GeodeticOrigin, common::GeodeticOrigin>);
  static_assert(std::is_same_v<Geodetic, common::Geodetic>);
  const GeodeticOrigin o{47.397742, 8.545594, 488.0, 0.0};
  const Geodetic p{47.3980, 8.5460, 500.0};
  const Eigen::Vector3d ned = ned_from_geodetic(o, p);
  const Eigen::Vector3d enu = enu_from_geodetic(o, p);
  EXPECT_DOUBLE_EQ(enu.x(), ned.y());
  EXPECT_DOUBLE_EQ(enu.z(), -ned.z());
  const Geodetic back = geodetic_from_enu(o, enu);
  EXPECT_NEAR(back.lat_deg, p.lat_deg, kRoundTripTol);
  EXPECT_NEAR(back.lon_deg, p.lon_deg, kRoundTripTol);
  EXPECT_NEAR(back.alt_m, p.alt_m, kRoundTripTol);
  EXPECT_NEAR(enu_yaw_from_ned(0.0), common::kPi / 2, kYawTol_rad);  // north
  EXPECT_NEAR(enu_yaw_from_ned(common::kPi / 2), 0.0, kYawTol_rad);  // east
  EXPECT_NEAR(ned_yaw_from_enu(enu_yaw_from_ned(1.0)), 1.0, kYawTol_rad);
}

TEST(Geodesy, TelemetryOriginIsZeroUntilTheVehicleSendsIt) {
  // a default GeodeticOrigin is the server's default home; the telemetry's stays zero until
  // GPS_GLOBAL_ORIGIN arrives, so an unset origin is never mistaken for a real one
  const Telemetry t;
  EXPECT_FALSE(t.origin_set);
  EXPECT_EQ(t.origin.lat_deg, 0.0);
  EXPECT_EQ(t.origin.lon_deg, 0.0);
  EXPECT_EQ(t.origin.alt_m, 0.0);
  EXPECT_NE(GeodeticOrigin{}.lat_deg, 0.0);
}

TEST(LoopConfig, FromEnvironment) {
  unsetenv("UAVSIM_LOCKSTEP");
  EXPECT_EQ(LoopConfig::from_env().clock, LoopConfig::Clock::kHost);
  setenv("UAVSIM_LOCKSTEP", "10.0.0.2:5701/0.05", 1);
  LoopConfig c = LoopConfig::from_env();
  EXPECT_EQ(c.clock, LoopConfig::Clock::kLockstep);
  EXPECT_EQ(c.lockstep_host, "10.0.0.2");
  EXPECT_EQ(c.lockstep_port, 5701);
  EXPECT_DOUBLE_EQ(c.lockstep_period_s, 0.05);
  setenv("UAVSIM_LOCKSTEP", "garbage", 1);
  auto l = EventLoop::create(LoopConfig::from_env());
  ASSERT_FALSE(l);
  EXPECT_EQ(l.code(), Error::kInvalidArgument);
  unsetenv("UAVSIM_LOCKSTEP");
}

class HostLoop : public ::testing::Test {
 protected:
  void SetUp() override {
    auto l = EventLoop::create(LoopConfig::host());
    ASSERT_TRUE(l) << l.message();
    loop_ = std::move(*l);
  }
  std::unique_ptr<EventLoop> loop_;
};

TEST_F(HostLoop, TimersFireInDeadlineOrder) {
  std::vector<int> order;
  loop_->call_after(0.03, [&] { order.push_back(3); });
  loop_->call_after(0.01, [&] { order.push_back(1); });
  const TimerId cancelled = loop_->call_after(0.02, [&] { order.push_back(99); });
  loop_->call_after(0.02, [&] { order.push_back(2); });
  EXPECT_TRUE(loop_->cancel(cancelled));
  const double t0 = loop_->now();
  ASSERT_TRUE(loop_->run_for(0.05));
  EXPECT_GE(loop_->now() - t0, 0.05);
  EXPECT_EQ(order, (std::vector<int>{1, 2, 3}));
  EXPECT_FALSE(loop_->cancel(cancelled));
}

TEST_F(HostLoop, PeriodicTimerAndRunUntil) {
  int n = 0;
  const TimerId id = loop_->call_every(0.01, [&] { ++n; });
  auto r = loop_->run_until([&] { return n >= 5; }, 1.0, "five ticks");
  ASSERT_TRUE(r) << r.message();
  loop_->cancel(id);
  r = loop_->run_until([] { return false; }, 0.02, "never");
  ASSERT_FALSE(r);
  EXPECT_EQ(r.code(), Error::kTimeout);
  EXPECT_NE(r.message().find("never"), std::string::npos);
}

TEST_F(HostLoop, PostFromAnotherThreadAndStop) {
  int ran = 0;
  std::thread t([&] {
    loop_->post([&] { ++ran; });
    loop_->stop();
  });
  loop_->run();
  t.join();
  EXPECT_EQ(ran, 1);
}

TEST_F(HostLoop, WatchesFileDescriptors) {
  int fds[2];
  ASSERT_EQ(pipe(fds), 0);
  std::string got;
  ASSERT_TRUE(loop_->watch_fd(fds[0], EventLoop::kReadable, [&](std::uint32_t what) {
    if (what & EventLoop::kReadable) {
      char buf[16];
      const ssize_t n = read(fds[0], buf, sizeof(buf));
      if (n > 0) got.append(buf, static_cast<std::size_t>(n));
    }
  }));
  loop_->call_after(0.01, [&] { [[maybe_unused]] auto n = write(fds[1], "hi", 2); });
  ASSERT_TRUE(loop_->run_until([&] { return got == "hi"; }, 1.0));
  loop_->unwatch_fd(fds[0]);
  close(fds[0]);
  close(fds[1]);
}

TEST_F(HostLoop, RunBusyOnTheHostClockJustRuns) {
  bool ran = false;
  loop_->run_busy(10.0, [&] { ran = true; });
  EXPECT_TRUE(ran);
  EXPECT_LT(loop_->now(), 5.0);
}

TEST_F(HostLoop, LoopThreadContract) {
  EXPECT_TRUE(loop_->in_loop_thread());
  bool other = true;
  std::thread t([&] { other = loop_->in_loop_thread(); });
  t.join();
  EXPECT_FALSE(other);
  EXPECT_DEATH(std::thread([&] { loop_->call_after(1.0, [] {}); }).join(), "not from its loop thread");
}

}  // namespace
}  // namespace uavsim::client
