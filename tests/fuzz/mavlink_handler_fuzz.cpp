// libFuzzer target past the MAVLink parser: fuzz bytes become well-formed messages (commands, setpoints,
// mission and parameter traffic) addressed to a live vehicle, which the endpoint's handlers apply to a
// flying flight controller in a MuJoCo simulation, stepping it between messages. Run with -timeout:
// an input that makes a handler or the controller loop (the angle wrap that spun on 1e30) is reported
// as a timeout; a sanitizer finding or non-finite vehicle state is a crash.
//
// Input: records of [kind byte][selector byte][the message's payload bytes]; kind picks the message,
// selector the command id for COMMAND_LONG/INT and MISSION_ITEM(_INT) (from the ones the endpoint
// handles), so random bytes reach the handlers instead of stopping at "unsupported".
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <memory>
#include <string>

#include "uavsim/common/mavlink/codec.hpp"
#include "uavsim/common/mavlink/parser.hpp"
#include "uavsim/common/mavlink/generated/messages.hpp"
#include "mavlink/vehicle_link.hpp"
#include "physics/world.hpp"
#include "sim/simulation.hpp"

namespace uavsim::server {
namespace {

namespace msg = mavlink::msg;

constexpr std::uint16_t kCommands[] = {400, 176, 22, 21, 20, 17, 115, 178, 300, 224,
                                       192, 205, 1000, 410, 520, 512, 511, 510, 42428};
constexpr std::uint16_t kMissionCommands[] = {16, 22, 21, 20, 19, 178, 115};
constexpr double kResetAfter_s = 300.0;  // sim time before a fresh world (keeps inputs comparable)

void check(bool ok) {
  if (!ok) __builtin_trap();
}

struct Harness {
  std::unique_ptr<sim::Simulation> sim;
  mavlink::EndpointConfig config;
  mavlink::StatCounters stats;
  mavlink::SigningKeyCell signing;
  std::unique_ptr<mavlink::VehicleLink> link;
  std::shared_ptr<mavlink::Outbox> outbox;
  mavlink::Parser parser;

  Harness() {
    physics::ComposeOptions o;
    o.models_dir = UAVSIM_MODELS_DIR;
    sim = std::make_unique<sim::Simulation>(
        physics::World::load(std::string(UAVSIM_MODELS_DIR) + "/worlds/empty.xml", o), sim::SimConfig{});
    link = std::make_unique<mavlink::VehicleLink>(*sim, 0, config, stats, signing);
    fresh();
  }

  // a new flight: the world reset, GUIDED, armed, taking off
  void fresh() {
    sim->reset(1);
    if (outbox) link->on_disconnect(1);
    outbox = std::make_shared<mavlink::Outbox>(1u << 20);
    link->on_connect(1, outbox);
    fc::FlightController& fc = sim->fc(0);
    fc.set_mode(fc::Mode::kGuided);
    fc.arm(true);
    fc.takeoff(5.0);
    control_steps(50);
  }

  void control_steps(int n) {
    for (int k = 0; k < n; ++k) {
      for (int s = 0; s < sim->control_decimation(); ++s) sim->step();
      link->on_control_step();
      std::string sent;
      outbox->buffer().take_queued(sent);  // the client "reads" everything
    }
  }

  // encodes m as a client would send it and hands the parsed frame to the endpoint
  template <class M>
  void deliver(const M& m) {
    mavlink::FrameHeader h;
    h.sysid = 255;
    h.compid = 190;
    const mavlink::EncodedFrame f = mavlink::encode(h, m);
    check(!f.empty());
    parser.feed(f.view(), [&](const mavlink::Frame& frame) { link->on_frame(1, frame, sim->fc(0)); });
  }
};

// one message of type M from the fuzz bytes, aimed at the vehicle
template <class M>
std::size_t message_from(const std::uint8_t* data, std::size_t size, std::uint8_t selector, M* m) {
  std::uint8_t payload[mavlink::kMaxPayloadLen] = {};
  const std::size_t n = std::min<std::size_t>(size, M::kMaxLen);
  std::memcpy(payload, data, n);
  *m = M::decode(payload);
  if constexpr (requires { m->target_system; }) m->target_system = 1;
  if constexpr (requires { m->target_component; }) m->target_component = 1;
  if constexpr (requires { m->command; }) {
    if constexpr (std::is_same_v<M, msg::MissionItemInt> || std::is_same_v<M, msg::MissionItem>) {
      m->command = kMissionCommands[selector % std::size(kMissionCommands)];
    } else {
      m->command = kCommands[selector % std::size(kCommands)];
    }
  }
  if constexpr (requires { m->mission_type; }) m->mission_type = 0;
  return n;
}

template <class... M>
std::size_t deliver_one(Harness& h, std::uint8_t kind, std::uint8_t selector, const std::uint8_t* data,
                        std::size_t size) {
  std::size_t used = 0;
  std::size_t index = 0;
  const std::size_t pick = kind % sizeof...(M);
  (
      [&] {
        if (index++ != pick) return;
        M m;
        used = message_from(data, size, selector, &m);
        h.deliver(m);
      }(),
      ...);
  return used;
}

}  // namespace
}  // namespace uavsim::server

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace uavsim::server;
  static Harness h;
  if (h.sim->runtime(0).crashed || h.sim->time_s() > kResetAfter_s) h.fresh();
  std::size_t at = 0;
  while (at + 2 <= size) {
    const std::uint8_t kind = data[at], selector = data[at + 1];
    at += 2;
    at += deliver_one<msg::CommandLong, msg::CommandInt, msg::SetMode, msg::SetPositionTargetLocalNed,
                      msg::SetPositionTargetGlobalInt, msg::SetAttitudeTarget, msg::MissionCount,
                      msg::MissionItemInt, msg::MissionItem, msg::MissionRequestInt, msg::MissionSetCurrent,
                      msg::MissionClearAll, msg::ParamSet, msg::RequestDataStream,
                      msg::GimbalManagerSetPitchyaw, msg::Heartbeat>(h, kind, selector, data + at, size - at);
    h.control_steps(1);
  }
  // let what was commanded run: mission items, yaw targets, setpoints
  h.control_steps(25);
  const fc::TruthState t = h.sim->truth(0);
  check(t.position_enu_m.allFinite() && t.q_enu_body.coeffs().allFinite());
  return 0;
}
