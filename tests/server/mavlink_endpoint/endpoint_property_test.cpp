// The MAVLink edge as a property (issue 29): every numeric field of every message the endpoint
// accepts, fed with the values that break naive code — NaN, +-inf, +-FLT_MAX (what 1e308 becomes in
// a float field), the smallest denormal, 2^63 and -0.0 in float fields, the extremes of integer
// fields — gets an answer where the protocol has one (COMMAND_ACK, MISSION_ACK, PARAM_VALUE), never
// a non-finite state, never a stalled loop (each test steps the simulation through its barrage),
// and leaves a vehicle that still flies. The hand-picked cases of endpoint_range_test.cpp say what
// each refusal is; this file says that no field was forgotten.
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "test_gcs.hpp"
#include "uavsim/common/angles.hpp"

namespace uavsim::server::mavlink::testing {
namespace {

using common::kPi;
constexpr int kAccepted = 0;
constexpr double kTakeoffAltM = 3.0;
constexpr double kAltTolM = 0.5;
constexpr double kHeadingTolRad = 0.15;
constexpr double kRestoreTol = 1e-6;  // a parameter restored through a float field
constexpr double kAnswerWithinSimS =
    5.0;                               // a burst of commands is answered within a few control steps
constexpr double kStreamCheckS = 1.0;  // sim time over which a stream's rate is counted

// The float values each float field is fed.
const std::array<float, 8> kHostileFloats = {
    std::numeric_limits<float>::quiet_NaN(), std::numeric_limits<float>::infinity(),
    -std::numeric_limits<float>::infinity(), std::numeric_limits<float>::max(),
    -std::numeric_limits<float>::max(),      std::numeric_limits<float>::denorm_min(),
    9.223372036854775808e18f /* 2^63 */,     -0.0f};
const std::array<std::int32_t, 4> kHostileInt32 = {std::numeric_limits<std::int32_t>::min(),
                                                   std::numeric_limits<std::int32_t>::max(), -1, 0};

// Every command the endpoint maps (command_mapper.cpp), and two it does not know.
const std::array<std::uint16_t, 21> kCommands = {400 /* ARM_DISARM */,
                                                 176 /* DO_SET_MODE */,
                                                 22 /* NAV_TAKEOFF */,
                                                 21 /* NAV_LAND */,
                                                 20 /* NAV_RTL */,
                                                 17 /* NAV_LOITER_UNLIM */,
                                                 115 /* CONDITION_YAW */,
                                                 178 /* CHANGE_SPEED */,
                                                 300 /* MISSION_START */,
                                                 224 /* SET_MISSION_CUR */,
                                                 192 /* DO_REPOSITION */,
                                                 205 /* DO_MOUNT_CONTROL */,
                                                 1000 /* GIMBAL_PITCHYAW */,
                                                 410 /* GET_HOME */,
                                                 520 /* AP_CAPABILITIES */,
                                                 512 /* REQUEST_MESSAGE */,
                                                 511 /* SET_MSG_INTERVAL */,
                                                 510 /* GET_MSG_INTERVAL */,
                                                 42428 /* SEND_BANNER */,
                                                 0 /* unknown */,
                                                 31999 /* unknown */};

bool finite_state(const fc::TruthState& s) {
  return s.position_enu_m.allFinite() && s.velocity_enu_m_s.allFinite() &&
         s.q_enu_body.coeffs().allFinite() && s.rate_body_rad_s.allFinite();
}

class PropertyTest : public EndpointTest {
 protected:
  // GUIDED, armed, at 3 m: the state in which most inputs take effect
  void fly(TestGcs& g) {
    if (!sim_->fc(0).armed())
      wait_gps_ready(g);  // SYS_STATUS reports the pre-arm checks while disarmed
    ASSERT_EQ(command(g, MavCmd::DoSetMode, {1, 4}), kAccepted);
    if (!sim_->fc(0).armed()) {
      ASSERT_EQ(command(g, MavCmd::ComponentArmDisarm, {1}), kAccepted);
    }
    (void)command(g, MavCmd::NavTakeoff,
                  {0, 0, 0, 0, 0, 0, static_cast<float>(kTakeoffAltM)});  // refused when airborne
    hold_at(g, kTakeoffAltM);
  }

  // a GUIDED position target over the origin; returns once telemetry says the vehicle is there
  void hold_at(TestGcs& g, double alt_m) {
    msg::SetPositionTargetLocalNed sp;
    sp.target_system = 1;
    sp.coordinate_frame = 1;
    sp.type_mask = 0x0DF8;  // position only
    sp.z = static_cast<float>(-alt_m);
    g.send(sp);
    sync_client(g);
    ASSERT_TRUE(step_until(
        g,
        [&] {
          const auto p = g.last<msg::GlobalPositionInt>();
          return p && std::abs(p->relative_alt / 1000.0 - alt_m) < kAltTolM;
        },
        60.0))
        << "the vehicle did not come back to " << alt_m << " m";
  }

  // after a barrage: the world is finite, the endpoint still talks, and the vehicle still obeys
  void expect_still_flies(TestGcs& g, const std::string& after) {
    ASSERT_TRUE(finite_state(sim_->truth(0))) << "after " << after;
    const std::size_t beats = g.count<msg::Heartbeat>();
    ASSERT_TRUE(step_until(
        g, [&] { return g.count<msg::Heartbeat>() > beats + 1; }, 3.0))
        << "no heartbeat after " << after;
    ASSERT_NO_FATAL_FAILURE(fly(g)) << "after " << after;
    ASSERT_EQ(command(g, MavCmd::ConditionYaw, {90, 90, 0, 0}), kAccepted) << "after " << after;
    const double want = kPi / 2;  // ATTITUDE.yaw is NED: 90 deg is east
    EXPECT_TRUE(step_until(
        g,
        [&] {
          const auto a = g.last<msg::Attitude>();
          return a && std::abs(std::remainder(a->yaw - want, 2 * kPi)) < kHeadingTolRad;
        },
        15.0))
        << "the vehicle did not turn after " << after;
  }

  // sends every message of a burst, then steps until `answers()` has grown by the burst's size
  template <class Msg>
  void send_burst(TestGcs& g, const std::vector<Msg>& burst,
                  const std::function<std::size_t()>& answers, const std::string& what) {
    const std::size_t before = answers();
    for (const Msg& m : burst) g.send(m);
    sync_client(g);
    EXPECT_TRUE(step_until(
        g, [&] { return answers() >= before + burst.size(); }, kAnswerWithinSimS))
        << what << ": " << answers() - before << " answers to " << burst.size() << " messages";
    ASSERT_TRUE(finite_state(sim_->truth(0))) << what;
  }

  // one setpoint field of message Msg, with a type mask that makes the controller use it
  template <class Msg>
  struct SetpointField {
    const char* name;
    float Msg::*field;
    std::uint16_t mask;
  };

  // each field fed every hostile float: non-finite ones are counted as rejected, none makes the
  // state non-finite, and the vehicle comes back to its hold point after each field
  template <class Msg>
  void setpoint_barrage(TestGcs& g, const std::string& what,
                        const std::vector<SetpointField<Msg>>& fields,
                        const std::function<Msg(std::uint16_t)>& base) {
    for (const SetpointField<Msg>& f : fields) {
      for (const float v : kHostileFloats) {
        const auto rejected = server_->stats(0).rejected_inputs;
        Msg sp = base(f.mask);
        sp.*(f.field) = v;
        g.send(sp);
        sync_client(g);
        step_for(0.1);
        ASSERT_TRUE(finite_state(sim_->truth(0))) << what << " " << f.name << " = " << v;
        if (!std::isfinite(v)) {
          EXPECT_EQ(server_->stats(0).rejected_inputs, rejected + 1)
              << what << " " << f.name << " = " << v;
        }
      }
      ASSERT_NO_FATAL_FAILURE(hold_at(g, kTakeoffAltM)) << "after " << what << " " << f.name;
    }
  }
};

TEST_F(PropertyTest, EveryCommandLongParameterGetsAnAckForEveryHostileValue) {
  auto g = connect();
  ASSERT_NO_FATAL_FAILURE(fly(*g));
  for (const std::uint16_t cmd : kCommands) {
    std::vector<msg::CommandLong> burst;
    for (int field = 0; field < 7; ++field) {
      for (const float v : kHostileFloats) {
        msg::CommandLong c;
        c.target_system = 1;
        c.target_component = 1;
        c.command = cmd;
        float* params[] = {&c.param1, &c.param2, &c.param3, &c.param4,
                           &c.param5, &c.param6, &c.param7};
        *params[field] = v;
        burst.push_back(c);
      }
    }
    const auto acks = [&] {
      std::size_t n = 0;
      for (const auto& a : g->all<msg::CommandAck>()) n += a.command == cmd;
      return n;
    };
    ASSERT_NO_FATAL_FAILURE(send_burst(*g, burst, acks, "COMMAND_LONG " + std::to_string(cmd)));
  }
  expect_still_flies(*g, "the COMMAND_LONG barrage");
}

TEST_F(PropertyTest, EveryCommandIntFieldGetsAnAckForEveryHostileValue) {
  auto g = connect();
  ASSERT_NO_FATAL_FAILURE(fly(*g));
  for (const std::uint16_t cmd : kCommands) {
    std::vector<msg::CommandInt> burst;
    const auto base = [&] {
      msg::CommandInt c;
      c.target_system = 1;
      c.target_component = 1;
      c.command = cmd;
      c.frame = 6;  // GLOBAL_RELATIVE_ALT_INT
      return c;
    };
    for (int field = 0; field < 5; ++field) {
      for (const float v : kHostileFloats) {
        msg::CommandInt c = base();
        float* params[] = {&c.param1, &c.param2, &c.param3, &c.param4, &c.z};
        *params[field] = v;
        burst.push_back(c);
      }
    }
    for (const std::int32_t v : kHostileInt32) {
      msg::CommandInt cx = base(), cy = base();
      cx.x = v;
      cy.y = v;
      burst.push_back(cx);
      burst.push_back(cy);
    }
    const auto acks = [&] {
      std::size_t n = 0;
      for (const auto& a : g->all<msg::CommandAck>()) n += a.command == cmd;
      return n;
    };
    ASSERT_NO_FATAL_FAILURE(send_burst(*g, burst, acks, "COMMAND_INT " + std::to_string(cmd)));
  }
  expect_still_flies(*g, "the COMMAND_INT barrage");
}

// Setpoint streams have no acknowledgement: a non-finite value in a field the type mask uses is
// counted as a rejected input and never applied; the finite extremes may be applied (clamped by the
// controller) but the state stays finite.
TEST_F(PropertyTest, SetpointFieldsRejectNonFiniteValuesAndSurviveExtremes) {
  auto g = connect();
  ASSERT_NO_FATAL_FAILURE(fly(*g));
  const auto non_finite = [](float v) { return !std::isfinite(v); };
  // each field with a type mask that makes the controller use it (bits: ignore x,y,z | vx,vy,vz |
  // ax,ay,az | force | yaw | yaw rate)
  constexpr std::uint16_t kPos = 0x0DF8, kVel = 0x0DC7, kAcc = 0x0C3F, kYawRate = 0x05C7;
  constexpr std::uint16_t kPosYaw = kPos & ~0x0400;
  using Local = msg::SetPositionTargetLocalNed;
  using Global = msg::SetPositionTargetGlobalInt;
  const std::vector<SetpointField<Local>> local = {{"x", &Local::x, kPos},
                                                   {"y", &Local::y, kPos},
                                                   {"z", &Local::z, kPos},
                                                   {"vx", &Local::vx, kVel},
                                                   {"vy", &Local::vy, kVel},
                                                   {"vz", &Local::vz, kVel},
                                                   {"afx", &Local::afx, kAcc},
                                                   {"afy", &Local::afy, kAcc},
                                                   {"afz", &Local::afz, kAcc},
                                                   {"yaw", &Local::yaw, kPosYaw},
                                                   {"yaw_rate", &Local::yaw_rate, kYawRate}};
  ASSERT_NO_FATAL_FAILURE(setpoint_barrage<Local>(*g, "local", local, [](std::uint16_t mask) {
    Local sp;
    sp.target_system = 1;
    sp.coordinate_frame = 1;
    sp.type_mask = mask;
    sp.z = -static_cast<float>(kTakeoffAltM);
    return sp;
  }));

  const std::vector<SetpointField<Global>> global = {{"alt", &Global::alt, kPos},
                                                     {"vx", &Global::vx, kVel},
                                                     {"vy", &Global::vy, kVel},
                                                     {"vz", &Global::vz, kVel},
                                                     {"afx", &Global::afx, kAcc},
                                                     {"afy", &Global::afy, kAcc},
                                                     {"afz", &Global::afz, kAcc},
                                                     {"yaw", &Global::yaw, kPosYaw},
                                                     {"yaw_rate", &Global::yaw_rate, kYawRate}};
  const auto home = g->last<msg::GlobalPositionInt>();
  ASSERT_TRUE(home);
  const auto global_base = [&](std::uint16_t mask) {
    Global sp;
    sp.target_system = 1;
    sp.coordinate_frame = 6;  // GLOBAL_RELATIVE_ALT_INT
    sp.type_mask = mask;
    sp.lat_int = home->lat;
    sp.lon_int = home->lon;
    sp.alt = static_cast<float>(kTakeoffAltM);
    return sp;
  };
  ASSERT_NO_FATAL_FAILURE(setpoint_barrage<Global>(*g, "global", global, global_base));
  for (const std::int32_t v : kHostileInt32) {
    for (int field = 0; field < 2; ++field) {
      msg::SetPositionTargetGlobalInt sp = global_base(kPos);
      (field == 0 ? sp.lat_int : sp.lon_int) = v;
      g->send(sp);
      sync_client(*g);
      step_for(0.1);
      ASSERT_TRUE(finite_state(sim_->truth(0))) << (field == 0 ? "lat_int " : "lon_int ") << v;
    }
    ASSERT_NO_FATAL_FAILURE(hold_at(*g, kTakeoffAltM)) << "after lat/lon " << v;
  }

  // attitude targets (GUIDED's attitude path): quaternion, body rates, thrust
  for (int field = 0; field < 8; ++field) {
    for (const float v : kHostileFloats) {
      const auto rejected = server_->stats(0).rejected_inputs;
      msg::SetAttitudeTarget at;
      at.target_system = 1;
      at.q = {1, 0, 0, 0};
      at.thrust = 0.5f;
      at.type_mask = field < 4 ? 0x07 : 0x80;  // attitude only, or body rates only
      float* fields[] = {&at.q[0],          &at.q[1],           &at.q[2],
                         &at.q[3],          &at.body_roll_rate, &at.body_pitch_rate,
                         &at.body_yaw_rate, &at.thrust};
      *fields[field] = v;
      g->send(at);
      sync_client(*g);
      step_for(0.05);
      ASSERT_TRUE(finite_state(sim_->truth(0))) << "attitude field " << field << " = " << v;
      if (non_finite(v)) {
        EXPECT_EQ(server_->stats(0).rejected_inputs, rejected + 1)
            << "attitude field " << field << " = " << v;
      }
    }
    ASSERT_NO_FATAL_FAILURE(hold_at(*g, kTakeoffAltM)) << "after attitude field " << field;
  }

  // the gimbal manager's angles and rates
  for (int field = 0; field < 4; ++field) {
    for (const float v : kHostileFloats) {
      msg::GimbalManagerSetPitchyaw gp;
      gp.target_system = 1;
      gp.target_component = 1;
      float* fields[] = {&gp.pitch, &gp.yaw, &gp.pitch_rate, &gp.yaw_rate};
      *fields[field] = v;
      g->send(gp);
    }
    sync_client(*g);
    step_for(0.1);
    ASSERT_TRUE(finite_state(sim_->truth(0))) << "gimbal field " << field;
  }
  expect_still_flies(*g, "the setpoint barrage");
}

// PARAM_SET of every parameter to every hostile value: a non-finite value never changes it, any
// value leaves it finite and inside its documented range, and the vehicle flies once the values are
// restored.
TEST_F(PropertyTest, EveryParameterRefusesNonFiniteValuesAndStaysInItsRange) {
  auto g = connect();
  fc::FlightController& fc = sim_->fc(0);
  const std::vector<fc::ParamInfo> info = fc::param_info(*fc.param("BATT_CAPACITY"));
  ASSERT_EQ(info.size(), fc.param_names().size());
  for (const fc::ParamInfo& p : info) {
    const double before = *fc.param(p.name);
    for (const float v : kHostileFloats) {
      msg::ParamSet ps;
      ps.target_system = 1;
      ps.target_component = 1;
      set_string(ps.param_id, p.name);
      ps.param_value = v;
      g->send(ps);
      sync_client(*g);
      step_for(0.004);
      const double now = *fc.param(p.name);
      ASSERT_TRUE(std::isfinite(now)) << p.name << " = " << v;
      EXPECT_GE(now, p.min) << p.name << " = " << v;
      EXPECT_LE(now, p.max) << p.name << " = " << v;
      if (!std::isfinite(v)) {
        EXPECT_EQ(now, before) << p.name << " = " << v;
      }
    }
    // put it back, as a ground station would (the value the table held, which the same path
    // accepts)
    msg::ParamSet ps;
    ps.target_system = 1;
    ps.target_component = 1;
    set_string(ps.param_id, p.name);
    ps.param_value = static_cast<float>(before);
    g->send(ps);
    sync_client(*g);
    step_for(0.004);
    ASSERT_NEAR(*fc.param(p.name), before, kRestoreTol * std::max(1.0, std::abs(before))) << p.name;
  }
  ASSERT_TRUE(finite_state(sim_->truth(0)));
  expect_still_flies(*g, "the PARAM_SET barrage");
}

// Mission items carry the same numbers into AUTO: each hostile field gets a MISSION_ACK (accepted
// or an error), and the vehicle flies afterwards.
TEST_F(PropertyTest, EveryMissionItemFieldGetsAMissionAckForEveryHostileValue) {
  auto g = connect();
  const std::array<std::uint16_t, 7> items = {16 /* WAYPOINT */,
                                              22 /* TAKEOFF */,
                                              21 /* LAND */,
                                              115 /* YAW */,
                                              178 /* SPEED */,
                                              17 /* LOITER */,
                                              20 /* RTL */};
  for (const std::uint16_t cmd : items) {
    const auto base = [&] {
      msg::MissionItemInt it;
      it.target_system = 1;
      it.target_component = 1;
      it.seq = 1;
      it.command = cmd;
      it.frame = 3;  // GLOBAL_RELATIVE_ALT
      return it;
    };
    std::vector<msg::MissionItemInt> cases;
    for (int field = 0; field < 5; ++field) {
      for (const float v : kHostileFloats) {
        msg::MissionItemInt it = base();
        float* fields[] = {&it.param1, &it.param2, &it.param3, &it.param4, &it.z};
        *fields[field] = v;
        cases.push_back(it);
      }
    }
    for (const std::int32_t v : kHostileInt32) {
      msg::MissionItemInt ix = base(), iy = base();
      ix.x = v;
      iy.y = v;
      cases.push_back(ix);
      cases.push_back(iy);
    }
    for (const msg::MissionItemInt& it : cases) {
      const int ack =
          upload_mission(*g, 2, [&](int seq) { return seq == 0 ? msg::MissionItemInt{} : it; });
      ASSERT_NE(ack, -1) << "no MISSION_ACK for item " << cmd;
      ASSERT_TRUE(finite_state(sim_->truth(0)));
    }
  }
  expect_still_flies(*g, "the mission-item barrage");
}

// The integer-only messages at their extremes: sticks, RC overrides, time sync, stream rates,
// mission counts and indices, SET_MODE. Nothing allocates by a count from the wire, nothing streams
// faster than the control loop, and the vehicle flies afterwards.
TEST_F(PropertyTest, IntegerMessagesAtTheirExtremesLeaveTheVehicleFlying) {
  auto g = connect();
  ASSERT_NO_FATAL_FAILURE(fly(*g));
  constexpr std::int16_t kI16[] = {std::numeric_limits<std::int16_t>::min(),
                                   std::numeric_limits<std::int16_t>::max(), -1, 0};
  constexpr std::uint16_t kU16[] = {0, 1, 65534, 65535};
  for (const std::int16_t v : kI16) {
    msg::ManualControl mc;
    mc.target = 1;
    mc.x = mc.y = mc.z = mc.r = v;
    g->send(mc);
  }
  for (const std::uint16_t v : kU16) {
    msg::RcChannelsOverride rc;
    rc.target_system = 1;
    rc.target_component = 1;
    rc.chan1_raw = rc.chan2_raw = rc.chan3_raw = rc.chan4_raw = v;
    rc.chan5_raw = rc.chan6_raw = rc.chan7_raw = rc.chan8_raw = v;
    g->send(rc);
  }
  for (const std::int64_t v : {std::numeric_limits<std::int64_t>::min(),
                               std::numeric_limits<std::int64_t>::max(), std::int64_t{-1}}) {
    msg::Timesync ts;
    ts.tc1 = 0;
    ts.ts1 = v;
    g->send(ts);
  }
  for (const std::uint16_t v : kU16) {
    msg::MissionSetCurrent sc;
    sc.target_system = 1;
    sc.target_component = 1;
    sc.seq = v;
    g->send(sc);
  }
  // a count of 65535 opens an upload that is never finished: the endpoint must not reserve for it
  msg::MissionCount count;
  count.target_system = 1;
  count.target_component = 1;
  count.count = 65535;
  g->send(count);
  for (const std::uint32_t v : {0u, 0xFFFFFFFFu, 0x7FFFFFFFu}) {
    msg::SetMode sm;
    sm.target_system = 1;
    sm.base_mode = 0xFF;
    sm.custom_mode = v;
    g->send(sm);
  }
  // every stream asked for at 65535 Hz: served at most at the control rate
  for (std::uint8_t stream = 0; stream <= 12; ++stream) {
    msg::RequestDataStream rs;
    rs.target_system = 1;
    rs.target_component = 1;
    rs.req_stream_id = stream;
    rs.req_message_rate = 65535;
    rs.start_stop = 1;
    g->send(rs);
  }
  sync_client(*g);
  const std::size_t attitudes = g->count<msg::Attitude>();
  const double t0 = sim_->time_s();
  while (sim_->time_s() < t0 + kStreamCheckS) {
    for (int k = 0; k < sim_->control_decimation(); ++k) sim_->step();
    g->poll_once(0);
  }
  // (messages still on their way through the I/O thread only make the count smaller: it is an upper
  // bound)
  ASSERT_TRUE(finite_state(sim_->truth(0)));
  const double control_hz = 1.0 / sim_->control_dt_s();
  EXPECT_LE(static_cast<double>(g->count<msg::Attitude>() - attitudes),
            (sim_->time_s() - t0) * control_hz + 1.0)
      << "ATTITUDE streamed faster than the control loop";
  expect_still_flies(*g, "the integer barrage");
}

}  // namespace
}  // namespace uavsim::server::mavlink::testing
