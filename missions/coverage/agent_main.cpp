// coverage-agent: one or several agents of the coverage flock (the thesis the project descends
// from, chapter 3 and fig. 4.6), each on its own vehicle's MAVLink link and radio. Every agent is
// the pure state machine of agent.hpp, fed at a fixed rate (20 Hz) with what a real drone has: its
// telemetry (position, velocity, heading, armed, landed), the radio frames it heard and its camera
// footprint (computed by the agent from its own altitude and heading and the configured sensor
// size); nothing from the simulator's ground truth. Several agents in one process behave as
// several processes: each has its own link and radio, and frames between them go through the
// radio. UAVSIM_LOCKSTEP puts the process on the simulator's clock; the radio rides on that
// connection, so a frame that arrives at sim time t is seen at the first step at or after t.
//
// Standard output: one line per state change and note, and the agent's Area Parts Database as an
// `APD ...` line (apd_report.hpp) when it has changed (at most every --report-period seconds) and
// when the agent lands or fails; coverage-run scores the data that survived from them.
//
// The optimised variant (section 3.6, --gcs-ports): each agent also sends its APD to the ground
// station (coverage-gcs) over its own GCS link, best effort, when it changed (at most every
// --gcs-period seconds), and gives the station's latest map to its agent, whose leader merges it
// before planning. Nothing waits for the station: with its link cut the flock flies on as in the
// plain variant.
//
// usage: coverage-agent (--vehicle I | --vehicles A-B) --area WxH [options]; --help lists them.
// Exit status: 0 when every agent landed, 3 when one failed, 1 on a link or clock failure, 2 usage.
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "agent.hpp"
#include "apd_report.hpp"
#include "ground_station.hpp"
#include "radio_link.hpp"
#include "station_link.hpp"
#include "uavsim/client/event_loop.hpp"
#include "uavsim/client/vehicle.hpp"
#include "uavsim/common/parse_number.hpp"
#include "uavsim/mission/program.hpp"

using namespace uavsim::client;
using namespace uavsim::missions::coverage;

namespace {

constexpr double kMinStep_s = 0.02;  // the agent runs at 10-50 Hz
constexpr double kMaxStep_s = 0.1;
constexpr double kTakeoffRetry_s = 2.0;
constexpr double kLinger_s = 2.0;  // keep the links up a little after the end (last reports)

int usage() {
  std::fprintf(stderr, R"(usage: coverage-agent (--vehicle I | --vehicles A-B) --area WxH [options]
  --vehicle I             fly vehicle I (its simulator index; agent id = I)
  --vehicles A-B          fly vehicles A..B in this process (same behaviour as one process each)
  --area WxH              the rectangle: W along x (flight direction), H along y, metres
  --origin X,Y            its corner in the world ENU frame (default 0,0)
  --altitude M            survey altitude (default 20)
  --sensor XxY            sensor footprint at that altitude (default 7x10)
  --mavlink-host H        where the vehicles' MAVLink endpoints listen (default 127.0.0.1)
  --mavlink-base-port P   vehicle I on tcp:H:P+10*I (default 5760, ArduPilot SITL's convention)
  --mavlink-ports P,P,..  or one port per vehicle, in order
  --step S                agent period, sim seconds (default 0.05)
  --report-period S       APD report period (default 2)
  --status-period S       a status line (pose, holdings) every S seconds (default 0: none)
  --gcs-ports P,P,..      the optimised variant (thesis 3.6): each vehicle's GCS link to the
                          ground station (coverage-gcs) on udp:--gcs-host:P, one port per vehicle
  --gcs-host H            where those ports are (default 127.0.0.1)
  --gcs-period S          an agent sends its APD to the station at most every S seconds (default 1)
  --thesis-flocking       Algorithm 3 as the thesis writes it: R1 alone wherever a neighbour is
                          within D_R1 (default: where R1 pushes a follower towards the leader, it
                          also closes on the next agent that way, up to D_R1, at most 1 m/s)
  --pipelined             on the lockstep clock, a one-tick compute latency: the outputs of a step
                          go out at the next tick, and the simulator steps while the agents think
                          (deterministic; the GCS link's own UDP socket is not held back, so do
                          not combine with --gcs-ports where runs must repeat exactly)
)");
  return 2;
}

bool parse_pair(const char* s, char sep, double* a, double* b) {
  char* e = nullptr;
  *a = std::strtod(s, &e);
  if (e == s || *e != sep) return false;
  const char* s2 = e + 1;
  *b = std::strtod(s2, &e);
  return e != s2 && *e == '\0' && std::isfinite(*a) && std::isfinite(*b);
}

// "P,P,..." into ports; false if any is not a port number
bool parse_ports(const char* v, std::vector<int>* ports) {
  for (const char* p = v; *p;) {
    const char* comma = std::strchr(p, ',');
    const std::string one = comma ? std::string(p, comma) : std::string(p);
    int port = 0;
    if (!uavsim::common::parse_integer(one.c_str(), 1, 65535, &port)) return false;
    ports->push_back(port);
    p = comma ? comma + 1 : p + one.size();
  }
  return true;
}

// one agent with its vehicle link and radio
struct Flyer {
  int id = 0;
  std::unique_ptr<Vehicle> vehicle;
  std::unique_ptr<RadioLink> radio;
  FrameFit frames;               // the flock's frames fitted to the radio's largest
  std::unique_ptr<GcsLink> gcs;  // the optimised variant's link to the ground station
  std::unique_ptr<Agent> agent;
  AgentState last_state = AgentState::kTakingOff;
  int last_leader = -2;
  bool takeoff_wanted = false;
  bool takeoff_in_flight = false;  // GUIDED -> arm -> NAV_TAKEOFF sent, answers pending
  double takeoff_altitude_m = 0.0;
  double next_takeoff_try_s = 0.0;
  AreaParts reported;
  bool reported_once = false;
  double last_report_s = -1e9;
  double next_status_s = 0.0;
  bool finished = false;
  bool complete_logged = false;
  AreaParts sent_to_gcs;
  double next_gcs_s = 0.0;
  bool gcs_refused_logged = false;
};

// GUIDED, arm, NAV_TAKEOFF, each sent when the previous one is accepted (non-blocking: several
// agents share one event loop); a refusal ends the try (the caller tries again kTakeoffRetry_s
// later)
void send_takeoff(Flyer& f, const std::function<void(int, const std::string&)>& log) {
  auto give_up = [&f, log](const Result<void>& r) {
    f.takeoff_in_flight = false;
    if (!r) log(f.id, "take-off: " + r.message() + " (trying again)");
  };
  f.vehicle->set_mode_async(FlightMode::kGuided, [&f, give_up](Result<void> r) {
    if (!r) return give_up(r);
    f.vehicle->arm_async([&f, give_up](Result<void> r) {
      if (!r) return give_up(r);
      f.vehicle->takeoff_async(f.takeoff_altitude_m, give_up);
    });
  });
}

struct Options {
  int first = -1, last = -1;  // the vehicles flown
  CoverageConfig config;
  std::string host = "127.0.0.1";
  int base_port = 5760;
  std::vector<int> ports, gcs_ports;
  std::string gcs_host = "127.0.0.1";
  double gcs_period_s = 1.0;
  double step_s = 0.05, report_period_s = 2.0, status_period_s = 0.0;
  bool have_area = false;
  bool pipelined = false;
  int count() const { return last - first + 1; }
};

using Log = std::function<void(int, const std::string&)>;

// the command line into o; false: not usable (usage)
bool parse_options(int argc, char** argv, Options* o) {
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--help" || a == "-h") return false;
    if (a == "--pipelined") {
      o->pipelined = true;
      continue;
    }
    if (a == "--thesis-flocking") {
      o->config.gains.close_gap = false;
      continue;
    }
    if (i + 1 >= argc) return false;
    const char* v = argv[++i];
    double x = 0, y = 0;
    if (a == "--vehicle") {
      if (!uavsim::common::parse_integer(v, 0, kMaxAgents - 1, &o->first)) return false;
      o->last = o->first;
    } else if (a == "--vehicles") {
      const char* dash = std::strchr(v, '-');
      if (dash == nullptr) return false;
      const std::string lo(v, dash);
      if (!uavsim::common::parse_integer(lo.c_str(), 0, kMaxAgents - 1, &o->first) ||
          !uavsim::common::parse_integer(dash + 1, 0, kMaxAgents - 1, &o->last) ||
          o->last < o->first)
        return false;
    } else if (a == "--area") {
      if (!parse_pair(v, 'x', &x, &y)) return false;
      o->config.length_x_m = x;
      o->config.width_y_m = y;
      o->have_area = true;
    } else if (a == "--origin") {
      if (!parse_pair(v, ',', &x, &y)) return false;
      o->config.origin_x_m = x;
      o->config.origin_y_m = y;
    } else if (a == "--altitude") {
      o->config.altitude_m = std::strtod(v, nullptr);
    } else if (a == "--sensor") {
      if (!parse_pair(v, 'x', &x, &y)) return false;
      o->config.x_sensor_m = x;
      o->config.y_sensor_m = y;
    } else if (a == "--mavlink-host") {
      o->host = v;
    } else if (a == "--mavlink-base-port") {
      if (!uavsim::common::parse_integer(v, 1, 65535, &o->base_port)) return false;
    } else if (a == "--mavlink-ports") {
      if (!parse_ports(v, &o->ports)) return false;
    } else if (a == "--gcs-ports") {
      if (!parse_ports(v, &o->gcs_ports)) return false;
    } else if (a == "--gcs-host") {
      o->gcs_host = v;
    } else if (a == "--gcs-period") {
      o->gcs_period_s = std::strtod(v, nullptr);
    } else if (a == "--step") {
      o->step_s = std::strtod(v, nullptr);
    } else if (a == "--status-period") {
      o->status_period_s = std::strtod(v, nullptr);
    } else if (a == "--report-period") {
      o->report_period_s = std::strtod(v, nullptr);
    } else {
      return false;
    }
  }
  return o->first >= 0 && o->have_area;
}

// the options' values and counts; false after saying why
bool options_valid(const Options& o) {
  if (const std::string why = o.config.validate(); !why.empty()) {
    std::fprintf(stderr, "coverage-agent: %s\n", why.c_str());
    return false;
  }
  if (!(o.step_s >= kMinStep_s && o.step_s <= kMaxStep_s) ||
      !(o.report_period_s >= 0.1 && o.report_period_s <= 3600.0) ||
      !(o.status_period_s >= 0.0 && o.status_period_s <= 3600.0) ||
      !(o.gcs_period_s >= 0.05 && o.gcs_period_s <= 3600.0)) {
    std::fprintf(stderr,
                 "coverage-agent: --step must be in [0.02, 0.1], --report-period in "
                 "[0.1, 3600], --status-period in [0, 3600], --gcs-period in [0.05, 3600]\n");
    return false;
  }
  if (!o.ports.empty() && static_cast<int>(o.ports.size()) != o.count()) {
    std::fprintf(stderr, "coverage-agent: --mavlink-ports names %zu ports for %d vehicles\n",
                 o.ports.size(), o.count());
    return false;
  }
  if (!o.gcs_ports.empty() && static_cast<int>(o.gcs_ports.size()) != o.count()) {
    std::fprintf(stderr, "coverage-agent: --gcs-ports names %zu ports for %d vehicles\n",
                 o.gcs_ports.size(), o.count());
    return false;
  }
  return true;
}

// 1. the k-th vehicle's links: MAVLink, radio (its frames fitted to it), the station's; false
// after logging why
bool open_links(EventLoop& loop, const Options& o, int k, Flyer& f, const Log& log) {
  f.id = o.first + k;
  VehicleConfig vc;
  vc.telemetry_rate_hz = 20.0;
  vc.sim_vehicle = std::to_string(f.id);
  f.vehicle = std::make_unique<Vehicle>(loop, vc);
  const int port = o.ports.empty() ? o.base_port + 10 * f.id : o.ports[static_cast<size_t>(k)];
  const std::string address = "tcp:" + o.host + ":" + std::to_string(port);
  if (auto r = f.vehicle->connect(address, 30); !r) {
    log(f.id, "connect " + address + ": " + r.message());
    return false;
  }
  std::string error;
  f.radio = open_sim_radio(loop, f.id, &error);
  if (!f.radio) {
    log(f.id, "radio: " + error);
    return false;
  }
  // every frame sized from what the channel carries (127 bytes on the simple channel, 116 on
  // ns3's lr-wpan)
  const auto fit = fit_frames(f.radio->max_frame_bytes(), &error);
  if (!fit) {
    log(f.id, "radio: " + error);
    return false;
  }
  f.frames = *fit;
  if (!o.gcs_ports.empty()) {
    // the vehicle calls the station (its port learns our address from the first packet)
    f.gcs = GcsLink::open(
        station_link_config(static_cast<uint8_t>(f.id)),
        {"0.0.0.0", 0, o.gcs_host, static_cast<uint16_t>(o.gcs_ports[static_cast<size_t>(k)])},
        &error);
    if (!f.gcs) {
      log(f.id, "GCS link: " + error);
      return false;
    }
  }
  return true;
}

// every vehicle of this process ready, then every agent starts at the same tick, as separate
// processes would (waiting for one vehicle after the other started them a tick or more apart);
// false after logging why
bool start_agents(EventLoop& loop, const CoverageConfig& config, std::vector<Flyer>& flyers,
                  const Log& log) {
  (void)loop.run_until(
      [&] {
        for (const Flyer& f : flyers) {
          if (!f.vehicle->ready()) return false;
        }
        return true;
      },
      120, "the vehicles to be ready");
  for (Flyer& f : flyers) {
    if (auto r = f.vehicle->wait_ready(0); !r) {
      log(f.id, "wait ready: " + r.message());
      return false;
    }
    const Eigen::Vector2d home = f.vehicle->telemetry().position_enu_m.head<2>();
    f.agent = std::make_unique<Agent>(config, f.id, home, f.frames);
    f.reported = AreaParts(config.stripe_count());
    f.sent_to_gcs = AreaParts(config.stripe_count());
    char buf[128];
    std::snprintf(buf, sizeof buf, "ready at (%.1f, %.1f)", home.x(), home.y());
    log(f.id, buf);
  }
  return true;
}

// the agent's inputs: telemetry, the radio frames heard, the station's latest map (read at the
// steps only: what is heard at a step does not depend on the host's timing)
AgentInputs agent_inputs(Flyer& f, double now_s, const CoverageConfig& config) {
  const Telemetry& t = f.vehicle->telemetry();
  AgentInputs in;
  in.now_s = now_s;
  in.armed = t.armed;
  in.on_ground = t.landed == LandedState::kOnGround || t.landed == LandedState::kUnknown;
  in.position_enu_m = t.position_enu_m;
  in.velocity_enu_m_s = t.velocity_enu_m_s;
  in.yaw_enu_rad = enu_yaw_from_ned(t.yaw_rad);
  in.received = f.radio->take_received();
  if (f.gcs) {
    for (const GcsMessage& m : f.gcs->take_received()) {
      if (m.topic == kTopicStationMap) {
        if (auto map = decode_apd(m.payload, config.stripe_count())) in.gcs_map = *map;
      }
    }
  }
  return in;
}

// the agent's action on the vehicle; a take-off is sent until the vehicle is up (a refused arm is
// tried again), without blocking: the other agents of this process step on while the commands
// are answered
void fly(Flyer& f, const AgentOutputs& out, double now_s, const Log& log) {
  switch (out.action) {
    case AgentOutputs::Action::kNone:
      break;
    case AgentOutputs::Action::kTakeOff:
      f.takeoff_wanted = true;
      f.takeoff_altitude_m = out.takeoff_altitude_m;
      f.next_takeoff_try_s = now_s;
      break;
    case AgentOutputs::Action::kVelocity:
      f.takeoff_wanted = false;
      // R2 as a heading target for the autopilot's yaw controller (agent.hpp)
      if (auto r = out.yaw_enu_rad
                       ? f.vehicle->set_velocity_enu_yaw(out.velocity_enu_m_s, *out.yaw_enu_rad)
                       : f.vehicle->set_velocity_enu(out.velocity_enu_m_s, out.yaw_rate_rad_s);
          !r)
        log(f.id, "velocity: " + r.message());
      break;
    case AgentOutputs::Action::kLand:
      f.takeoff_wanted = false;
      f.vehicle->land_async([&f, log](Result<void> r) {
        if (!r) log(f.id, "land: " + r.message());
      });
      break;
  }
  if (f.takeoff_wanted && !f.takeoff_in_flight && !f.vehicle->telemetry().armed &&
      now_s >= f.next_takeoff_try_s && f.agent->state() == AgentState::kTakingOff) {
    f.next_takeoff_try_s = now_s + kTakeoffRetry_s;
    f.takeoff_in_flight = true;
    send_takeoff(f, log);
  }
}

// the radio's frames, and what we acquired to the station (best effort)
void transmit(Flyer& f, const AgentOutputs& out, double now_s, double gcs_period_s,
              const Log& log) {
  for (const Frame& frame : out.broadcast) (void)f.radio->broadcast(frame);
  if (f.gcs && now_s >= f.next_gcs_s && !(f.agent->own() == f.sent_to_gcs)) {
    f.next_gcs_s = now_s + gcs_period_s;
    f.sent_to_gcs = f.agent->own();
    const GcsLinkStatus st = f.gcs->publish(kTopicAgentApd, encode_apd(f.sent_to_gcs));
    if (st != GcsLinkStatus::kOk && !f.gcs_refused_logged) {
      f.gcs_refused_logged = true;
      log(f.id, std::string("GCS link refused our APD: ") + gcs_link_status_name(st));
    }
  }
}

// what the leader's map misses (a debugging aid with --status-period)
std::string map_gaps(const AreaParts& m, double width_y_m) {
  std::string gaps;
  for (int st = 0, n = 0; st < m.stripe_count() && n < 4; ++st) {
    if (auto lo = m.lowest_uncovered(st, width_y_m)) {
      char buf[96];
      std::snprintf(buf, sizeof buf, " [%d: from %.2f, %zu intervals]", st, *lo,
                    m.stripe(st).size());
      gaps += buf;
      ++n;
    }
  }
  return gaps;
}

// what the launcher reads: the end of the mission, state changes, the status lines
void log_progress(Flyer& f, const AgentInputs& in, const Options& o, const Log& log) {
  if (f.agent->mission_complete() != f.complete_logged) {
    f.complete_logged = f.agent->mission_complete();
    if (f.complete_logged) log(f.id, "mission complete: the query found the rectangle covered");
  }
  const AgentState s = f.agent->state();
  if (s != f.last_state || f.agent->leader() != f.last_leader) {
    f.last_state = s;
    f.last_leader = f.agent->leader();
    log(f.id, std::string("state ") + agent_state_name(s) + " leader " +
                  std::to_string(f.agent->leader()));
    if (o.status_period_s > 0 && s == AgentState::kDeploying && f.agent->last_map())
      log(f.id, "map gaps:" + map_gaps(*f.agent->last_map(), o.config.width_y_m));
  }
  if (o.status_period_s > 0 && in.now_s >= f.next_status_s) {
    const Telemetry& t = f.vehicle->telemetry();
    f.next_status_s = in.now_s + o.status_period_s;
    char buf[200];
    std::snprintf(buf, sizeof buf,
                  "status at (%.1f, %.1f, %.1f) yaw %.2f speed %.1f, holds %.1f %%, %zu in ADB",
                  t.position_enu_m.x(), t.position_enu_m.y(), t.position_enu_m.z(), in.yaw_enu_rad,
                  t.velocity_enu_m_s.head<2>().norm(),
                  100.0 * f.agent->own().covered_fraction(o.config.width_y_m),
                  f.agent->adb().records().size());
    log(f.id, buf);
  }
}

// the agent's end: its counters and its sim seconds in each state (thesis fig. 4.9), in
// AgentState order
void log_end(const Flyer& f, AgentState s, const Log& log) {
  char buf[160];
  std::snprintf(buf, sizeof buf, "over: %s, %d queries started, %lu radio frames refused",
                agent_state_name(s), f.agent->queries_started(), f.radio->refused());
  log(f.id, buf);
  std::string times = "time in states:";
  for (int k = 0; k < kAgentStateCount; ++k) {
    std::snprintf(buf, sizeof buf, " %.2f", f.agent->time_in_state()[static_cast<size_t>(k)]);
    times += buf;
  }
  log(f.id, times);
}

// the agent's APD as a line for the launcher
void report(Flyer& f, double now_s) {
  std::printf("%s\n", encode_apd_report(f.id, now_s, f.agent->own()).c_str());
  std::fflush(stdout);
  f.reported = f.agent->own();
  f.reported_once = true;
  f.last_report_s = now_s;
}

// 2. one agent's step; true once it is over
bool step_flyer(Flyer& f, uavsim::mission::ProgramLoop& program, const Options& o, const Log& log) {
  const double now_s = program.loop().now();
  // the station's link keeps going after the end (what is still unacknowledged goes out)
  if (f.gcs) (void)f.gcs->service(program.now_us());
  if (f.finished) return true;
  const AgentInputs in = agent_inputs(f, now_s, o.config);
  const AgentOutputs out = f.agent->step(in);
  if (!out.note.empty()) log(f.id, out.note);
  fly(f, out, now_s, log);
  transmit(f, out, now_s, o.gcs_period_s, log);
  log_progress(f, in, o, log);
  // a landed agent keeps its radio on until every agent it hears has landed (agent.hpp)
  const AgentState s = f.agent->state();
  const bool over = s == AgentState::kFailed || f.agent->flock_landed();
  if (over || (!(f.agent->own() == f.reported) && now_s - f.last_report_s >= o.report_period_s)) {
    report(f, now_s);
  }
  if (!over) return false;
  f.finished = true;
  // a dead drone's link is silent: what it had not sent yet is lost with it
  if (s == AgentState::kFailed) f.gcs.reset();
  log_end(f, s, log);
  return true;
}

}  // namespace

int main(int argc, char** argv) {
  Options o;
  if (!parse_options(argc, argv, &o)) return usage();
  if (!options_valid(o)) return 2;

  const auto program = uavsim::mission::ProgramLoop::create("coverage-agent");
  if (!program) return 1;
  EventLoop& loop = program->loop();
  const Log log = [&loop](int id, const std::string& s) {
    std::printf("agent %d t=%.2f %s\n", id, loop.now(), s.c_str());
    std::fflush(stdout);
  };

  // 1. links: MAVLink and radio of every vehicle, then wait until each is ready to fly
  std::vector<Flyer> flyers(static_cast<size_t>(o.count()));
  for (int k = 0; k < o.count(); ++k) {
    if (!open_links(loop, o, k, flyers[static_cast<size_t>(k)], log)) return 1;
  }
  if (!start_agents(loop, o.config, flyers, log)) return 1;

  // 2. the agents at a fixed rate (pipelined from here on, if asked: every link is up)
  loop.set_lockstep_pipelined(o.pipelined);
  double end_s = -1.0;
  while (end_s < 0 || loop.now() < end_s + kLinger_s) {
    if (auto r = loop.run_for(o.step_s); !r) {
      std::fprintf(stderr, "coverage-agent: clock: %s\n", r.message().c_str());
      return 1;
    }
    bool all_finished = true;
    for (Flyer& f : flyers) all_finished = step_flyer(f, *program, o, log) && all_finished;
    if (all_finished && end_s < 0) end_s = loop.now();
  }
  for (const Flyer& f : flyers) {
    if (f.agent->state() != AgentState::kLanded) return 3;
  }
  return 0;
}
