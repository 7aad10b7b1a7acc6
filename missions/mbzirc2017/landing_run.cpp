#include "landing_run.hpp"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iterator>
#include <regex>
#include <sstream>

#include "uavsim/client/sim_connection.hpp"
#include "uavsim/common/angles.hpp"
#include "uavsim/common/install_paths.hpp"
#include "uavsim/common/splitmix.hpp"

namespace uavsim::missions::mbzirc2017 {
namespace {

using client::SimConnection;
using client::SimMessage;
using Json = nlohmann::json;

constexpr double kLockstepPeriod_s = 0.05;  // the UAV program's and the fault injector's ticks
constexpr double kStayOnDeck_s = 5.0;       // scored: still carried this long after touchdown
constexpr double kPauseSlack_s =
    0.01;  // a pause_at holds the clock within a physics step of its time
constexpr double kTruckHistory_s = 10.0;  // ticks kept for lines stamped before the tick they meet
constexpr double kFirstPassBlackout_s = 14.0;  // longer than the 12 s search of Wait Until Visible
constexpr double kApproachBlackout_s = 4.0;    // longer than the 1 s after which the marker is lost
// --lose-low-off-centre: at this skid height over the deck, the GPS 1 m off and the camera black
constexpr double kLoseLowHeight_m = 1.0;
constexpr double kLoseLowGlitch_m = 1.0;
constexpr double kLoseLowBlackout_s = 6.0;
// over the deck: the body origin within the deck's half width of its centre
constexpr double kOverTheDeck_m = 1.1;

// The world with the truck's first speed replaced, written beside the temporary files (its include
// made absolute). Empty on failure.
std::string world_with_speed(const std::string& world, double kmh, uint64_t seed) {
  std::ifstream in(world);
  if (!in) return "";
  std::stringstream ss;
  ss << in.rdbuf();
  std::string text = ss.str();
  const std::string dir = world.substr(0, world.rfind('/') + 1);
  text = std::regex_replace(text, std::regex(R"(file="\.\./)"), "file=\"" + dir + "../");
  char speed[64];
  std::snprintf(speed, sizeof(speed), "data=\"%.6g 5 480 0\"", kmh);
  text = std::regex_replace(text, std::regex(R"((name="uavsim:truck:speed"\s+)data="[^"]*")"),
                            std::string("$1") + speed);
  const char* tmp = std::getenv("TMPDIR");
  const std::string path = std::string(tmp != nullptr && *tmp != '\0' ? tmp : "/tmp") +
                           "/mbzirc2017_" + std::to_string(getpid()) + "_" + std::to_string(seed) +
                           ".xml";
  std::ofstream out(path);
  out << text;
  return out ? path : "";
}

// A uniform number in [0, 1) from the seed and a stream number (splitmix64: the same on every
// platform, unlike the standard library's distributions).
double seeded_uniform(uint64_t seed, uint64_t stream) {
  const uint64_t z =
      common::splitmix64_mix(seed * common::kSplitMixGamma + (stream + 1) * 0xBF58476D1CE4E5B9ULL);
  return static_cast<double>(z >> 11) * 0x1.0p-53;
}

std::optional<std::vector<double>> world_numeric(const std::string& text, const std::string& name) {
  const std::regex re("name=\"" + name + "\"\\s+data=\"([^\"]*)\"");
  std::smatch m;
  if (!std::regex_search(text, m, re)) return std::nullopt;
  std::vector<double> v;
  std::istringstream in(m[1].str());
  for (double x = 0.0; in >> x;) v.push_back(x);
  return v;
}

// Fails (false, why) on numbers out of range: they would reach the lap time's division.
bool read_truck_schedule(const std::string& world, TruckSchedule* out, std::string* why) {
  std::ifstream in(world);
  if (!in) {
    *why = "cannot read " + world;
    return false;
  }
  std::stringstream ss;
  ss << in.rdbuf();
  const std::string text = ss.str();
  if (const auto t = world_numeric(text, "uavsim:truck:track")) {
    if (t->size() != 5 || !((*t)[0] > 0.0) || !((*t)[1] > 2.0 * (*t)[0]) || (*t)[1] > 1e4) {
      *why = world + ": uavsim:truck:track needs R_m D_m x_m y_m yaw_deg with D > 2 R > 0";
      return false;
    }
    out->track.circle_radius_m = (*t)[0];
    out->track.centre_separation_m = (*t)[1];
    out->track.centre_enu_m = Eigen::Vector2d((*t)[2], (*t)[3]);
    out->track.yaw_rad = (*t)[4] * common::kPi / 180.0;
  }
  if (const auto sp = world_numeric(text, "uavsim:truck:speed")) {
    if (sp->size() < 3 || !((*sp)[0] > 0.0) || !((*sp)[1] > 0.0) || (*sp)[0] > kMaxKmh ||
        (*sp)[1] > kMaxKmh || !((*sp)[2] >= 0.0)) {
      *why =
          world + ": uavsim:truck:speed needs speed1_kmh speed2_kmh switch_s (speeds in (0, 60])";
      return false;
    }
    out->speed1_kmh = (*sp)[0];
    out->speed2_kmh = (*sp)[1];
    out->switch_s = (*sp)[2];
  }
  return true;
}

// "uav0 t=12.35 state Intercept -> WaitUntilVisible: ..." => (12.35, "WaitUntilVisible")
std::optional<std::pair<double, std::string>> state_change(const std::string& line) {
  static const std::regex re(R"(t=([0-9.]+) state \w+ -> (\w+))");
  std::smatch m;
  if (!std::regex_search(line, m, re)) return std::nullopt;
  return std::make_pair(std::stod(m[1]), m[2].str());
}

int truck_contacts(const std::vector<std::string>& crashes) {
  int n = 0;  // crashes into any truck part (the deck is never a crash)
  for (const std::string& c : crashes) n += c.find("truck/") != std::string::npos;
  return n;
}

}  // namespace

bool LandingRun::on_deck_long_enough(double t) const {
  return landed_s_ >= 0 && t >= landed_s_ + kStayOnDeck_s - kPauseSlack_s;
}

int LandingRun::prepare() {
  // where on the eight the UAV starts: a fraction of a lap at the speed of its phase
  if (o_.random_truck_speed) {
    o_.truck_speed_kmh = kMinRuleKmh + (kMaxRuleKmh - kMinRuleKmh) * seeded_uniform(o_.seed, 100);
  }
  if (std::string why; !read_truck_schedule(o_.world, &schedule_, &why)) {
    std::fprintf(stderr, "mbzirc2017-run: %s\n", why.c_str());
    return 2;
  }
  if (o_.truck_speed_kmh > 0.0) schedule_.speed1_kmh = o_.truck_speed_kmh;
  track_.emplace(schedule_.track);
  if (o_.random_start_phase) o_.start_phase = seeded_uniform(o_.seed, 0);
  if (o_.start_phase) {
    const double kmh = truck_kmh();
    o_.start_time_s = (o_.slow_phase ? schedule_.switch_s : 0.0) +
                      *o_.start_phase * track_->length_m() / (kmh / 3.6);
    if (!o_.slow_phase && o_.start_time_s > schedule_.switch_s) {
      std::fprintf(stderr, "mbzirc2017-run: a lap at %.1f km/h is longer than the first phase\n",
                   kmh);
      return 2;
    }
  }
  for (int k = 0; k < o_.random_blackouts; ++k) {
    blackouts_.emplace_back(
        o_.start_time_s + kBlackoutFrom_s +
            (kBlackoutTo_s - kBlackoutFrom_s) * seeded_uniform(o_.seed, 1 + 2 * k),
        kBlackoutMin_s + (kBlackoutMax_s - kBlackoutMin_s) * seeded_uniform(o_.seed, 2 + 2 * k));
  }
  std::sort(blackouts_.begin(), blackouts_.end());
  try {
    const std::string models = common::find_models_dir("", UAVSIM_MODELS_DIR).path;
    near_miss_.emplace(load_truck_shape(models + "/objects/truck.xml"),
                       load_vehicle_shape(models + "/vehicles/hexa.xml"));
  } catch (const std::exception& e) {
    std::fprintf(stderr, "mbzirc2017-run: %s\n", e.what());
    return 2;
  }
  world_ = o_.world;
  if (o_.truck_speed_kmh > 0.0) {
    world_ = world_with_speed(o_.world, o_.truck_speed_kmh, o_.seed);
    if (world_.empty()) {
      fail("cannot write a world with the truck at " + std::to_string(o_.truck_speed_kmh) +
           " km/h");
      return 4;
    }
  }
  sim_s_ = o_.start_time_s;
  return 0;
}

launch::RunOptions LandingRun::server_options() const {
  launch::RunOptions server = o_;
  server.world = world_;  // the truck's speed written into it, if asked
  return server;
}

int LandingRun::run_floor() {
  // what mbzirc2017-uav subscribes to: its down-looking camera, grey (uav_main.cpp)
  return launch::run_floor(launch_, "mbzirc2017", server_options(), {}, "uav0_down:grey");
}

void LandingRun::start_server() {
  if (auto started = launch::start_run_server(launch_, server_options(), {}); !started) {
    fail(started.message());
  } else if (launch_.mavlink_port("uav0") == 0) {
    fail("the server did not start (no MAVLink port for uav0)");
  }
}

void LandingRun::on_uav_line(const std::string& line) {
  if (line.find("climb-away:") != std::string::npos) ++climb_aways_;
  if (line.find("position estimate stepped") != std::string::npos) ++estimate_steps_;
  if (auto s = state_change(line)) {
    if (s->second == "Approach" && !approach_s_) approach_s_ = s->first;
    states_.push_back(s->second);
    pending_states_.push_back(*s);
  }
}

void LandingRun::set_up() {
  SimConnection& api = launch_.api();
  // 1. hold the clock, start from t = 0 with this seed; the truck alone drives to the start time
  if (!api.pause() || !api.reset(o_.seed) || !api.subscribe_events()) {
    fail("the server refused the setup requests (pause, reset, subscribe_events)");
  } else if (o_.start_time_s > 0.0 &&
             !api.step_for(o_.start_time_s, std::max(60.0, o_.start_time_s))) {
    fail("the server did not run to the start time");
  } else if (!api.request({{"op", "pause_at"},
                           {"time_s", o_.start_time_s + o_.budget_s},
                           {"lockstep_empty", true}})) {
    // the clock stops by itself at the end (budget spent, the program gone, or 5 s on the deck):
    // the end of the run is the same every run
    fail("the server refused pause_at");
  }
  launch_.on_line([this](const std::string& child, const std::string& line) {
    if (child == "uav0") on_uav_line(line);
  });
  // 2. the UAV program (and the fault injector) on the lockstep clock, then let the clock go
  if (!failed_) {
    std::vector<std::string> argv{o_.uav, "--mavlink",
                                  "tcp:127.0.0.1:" + std::to_string(launch_.mavlink_port("uav0"))};
    if (!o_.run_dir.empty()) {
      // what its vision saw, frame by frame (uavsim-videolog-export makes an MP4 of it)
      vision_log_ = o_.run_dir + "/uav0_vision.vlog";
      argv.insert(argv.end(), {"--video-log", vision_log_});
    }
    auto u = launch_.spawn("uav0", argv, {launch_.lockstep_env(kLockstepPeriod_s)});
    if (!u) fail(u.message());
  }
  if (!failed_) {
    api.on_message("tick", [this](const SimMessage& m) {
      ticks_.emplace_back(m.json.value("tick", std::int64_t{0}), m.json.value("time", 0.0));
    });
    api.on_message("tick_results", [this](const SimMessage& m) {
      tick_truth_[m.json.value("time", -1.0)] = m.json.value("results", Json::array());
    });
    // the near misses' ground truth comes with each tick: no round trip while the clock waits
    if (!api.lockstep_join(kLockstepPeriod_s, 120.0, {{{"op", "vehicles"}}, {{"op", "truck"}}}))
      fail("the launcher could not join the lockstep");
  }
  if (!failed_) {
    if (auto w = launch_.wait_lockstep_clients(2, 120.0); !w) {
      fail("the UAV program did not join the lockstep");
    } else if (!api.resume()) {
      fail("resume refused");
    } else {
      launch_.say("mbzirc2017-run: seed " + std::to_string(o_.seed) +
                  ", UAV starts at t=" + std::to_string(static_cast<int>(o_.start_time_s)) +
                  " s, budget " + std::to_string(static_cast<int>(o_.budget_s)) + " s sim");
    }
  }
}

void LandingRun::on_sim_event(const Json& e) {
  const std::string type = e.value("type", ""), vehicle = e.value("vehicle_name", "");
  const std::string detail = e.value("detail", "");
  const double t = e.value("time", 0.0);
  if (type == "takeoff" && takeoff_s_ < 0) takeoff_s_ = t;
  if (type == "crash") crashes_.push_back(vehicle + " at " + std::to_string(t) + " s: " + detail);
  if (type == "landed_on_target" && landed_s_ < 0) {
    landed_s_ = t;
    part_at_touchdown_ = eight_part(*track_, truck_s_m_);
    // the clock is then still short of t + 5 s (a few ms of wall time at full speed)
    const auto r = launch_.api().request({{"op", "pause_at"}, {"time_s", t + kStayOnDeck_s}});
    if (r && r->value("time_s", 0.0) > t + kStayOnDeck_s) {
      launch_.say("mbzirc2017-run: the end-of-run pause came late (the run's end may vary)");
    }
    std::smatch mm;
    static const std::regex re(
        R"(relative speed ([0-9.]+) m/s, ([0-9.]+) m from the marker centre)");
    if (std::regex_search(detail, mm, re)) {
      relative_speed_m_s_ = std::stod(mm[1]);
      marker_distance_m_ = std::stod(mm[2]);
    }
  }
  if (type == "crash" || type == "takeoff" || type == "touchdown" || type == "landed_on_target" ||
      type == "disarmed") {
    char buf[320];
    std::snprintf(buf, sizeof(buf), "[event] t=%.2f %s %s %s", t, type.c_str(), vehicle.c_str(),
                  detail.c_str());
    launch_.say(buf);
  }
}

void LandingRun::blackout(double tick_s, double duration_s, const std::string& why) {
  if (!launch_.api().request(
          {{"op", "camera_blackout"}, {"camera", "uav0_down"}, {"duration_s", duration_s}})) {
    fail("camera_blackout refused");
  }
  char buf[160];
  std::snprintf(buf, sizeof(buf), "[fault] t=%.2f camera uav0_down black for %.1f s (%s)", tick_s,
                duration_s, why.c_str());
  launch_.say(buf);
}

// the near misses from the ground truth at the tick (the clock holds until done)
void LandingRun::track_near_miss(double tick_s) {
  // the vehicles' and the truck's ground truth at this tick, sent with it (with_tick); asked for
  // if it did not come (one round trip while the clock waits)
  Json v, t;
  const auto at = tick_truth_.find(tick_s);
  if (at != tick_truth_.end() && at->second.is_array() && at->second.size() == 2) {
    v = at->second[0].value("result", Json());
    t = at->second[1].value("result", Json());
  } else {
    const auto truth = launch_.api().request_all({{{"op", "vehicles"}}, {{"op", "truck"}}});
    if (truth[0] && truth[1]) {
      v = *truth[0];
      t = *truth[1];
    }
  }
  tick_truth_.erase(tick_truth_.begin(), tick_truth_.upper_bound(tick_s));
  if (!v.is_object() || !t.is_object()) return;
  for (const Json& veh : v.value("vehicles", Json::array())) {
    if (veh.value("name", "") != "uav0") continue;
    for (const Json& k : t.value("trucks", Json::array())) {
      const auto p = veh.value("position_enu_m", std::vector<double>{});
      const auto q = veh.value("q_enu_body", std::vector<double>{});
      const auto tp = k.value("position_enu_m", std::vector<double>{});
      if (p.size() != 3 || q.size() != 4 || tp.size() != 3) continue;
      near_miss_->add(Eigen::Vector3d(p[0], p[1], p[2]),
                      Eigen::Quaterniond(q[0], q[1], q[2], q[3]).normalized(),
                      Eigen::Vector3d(tp[0], tp[1], tp[2]), k.value("yaw_rad", 0.0));
      truck_s_m_ = k.value("s_m", 0.0);
      truck_yaw_rad_ = k.value("yaw_rad", 0.0);
      // the part of the eight at the approach's own tick: the program's line stamped with it may
      // come in before or after that tick is handled here (the two processes get the tick at
      // once), so it is looked up in the recent ticks, not taken from the tick it meets
      truck_s_by_tick_m_[tick_s] = truck_s_m_;
      truck_s_by_tick_m_.erase(truck_s_by_tick_m_.begin(),
                               truck_s_by_tick_m_.lower_bound(tick_s - kTruckHistory_s));
      if (approach_s_ && part_at_approach_.empty()) {
        const auto at = truck_s_by_tick_m_.upper_bound(*approach_s_ + 1e-9);
        if (at != truck_s_by_tick_m_.begin()) {
          part_at_approach_ = eight_part(*track_, std::prev(at)->second);
        }
      }
    }
  }
}

void LandingRun::inject_faults(double tick_s) {
  SimConnection& api = launch_.api();
  // the random blackouts due by this tick
  for (; next_blackout_ < blackouts_.size() && blackouts_[next_blackout_].first <= tick_s;
       ++next_blackout_) {
    blackout(tick_s, blackouts_[next_blackout_].second, "random");
  }
  // the marker lost low and off the centre: GPS 1 m towards the truck's rear, camera black
  if (const auto rel = near_miss_->latest();
      o_.lose_low_off_centre && lose_low_at_s_ < 0 && uav_state_ == "Approach" && rel &&
      rel->skid_height_m <= kLoseLowHeight_m && rel->p_truck_m.head<2>().norm() <= kOverTheDeck_m) {
    lose_low_at_s_ = tick_s;
    const Eigen::Vector2d back =
        -kLoseLowGlitch_m * Eigen::Vector2d(std::cos(truck_yaw_rad_), std::sin(truck_yaw_rad_));
    if (!api.request({{"op", "gps_glitch"},
                      {"vehicle", "uav0"},
                      {"offset_enu_m", {back.x(), back.y(), 0.0}}})) {
      fail("gps_glitch refused");
    }
    glitch_clear_s_ = tick_s + kLoseLowBlackout_s;
    char buf[200];
    std::snprintf(buf, sizeof(buf),
                  "[fault] t=%.2f GPS of uav0 off by (%+.2f, %+.2f) m for %.0f s, at %.2f m "
                  "above the deck",
                  tick_s, back.x(), back.y(), kLoseLowBlackout_s, rel->skid_height_m);
    launch_.say(buf);
    blackout(tick_s, kLoseLowBlackout_s, "low, off the centre");
  }
  if (glitch_clear_s_ >= 0.0 && tick_s >= glitch_clear_s_) {
    glitch_clear_s_ = -1.0;
    if (!api.request(
            {{"op", "gps_glitch"}, {"vehicle", "uav0"}, {"offset_enu_m", {0.0, 0.0, 0.0}}})) {
      fail("gps_glitch refused");
    }
    launch_.say("[fault] GPS of uav0 back");
  }
  // the program's state changes stamped before the tick: the blackouts they trigger
  for (auto it = pending_states_.begin(); it != pending_states_.end();) {
    if (it->first >= tick_s - 1e-9) {
      ++it;
      continue;
    }
    const std::string state = it->second;
    it = pending_states_.erase(it);
    uav_state_ = state;
    double duration = 0.0;
    if (o_.blackout_first_pass && state == "Intercept" && first_blackout_s_ < 0) {
      duration = kFirstPassBlackout_s;
      first_blackout_s_ = tick_s;
    } else if (o_.lose_in_approach && state == "Approach" && approach_blackout_s_ < 0) {
      duration = kApproachBlackout_s;
      approach_blackout_s_ = tick_s;
    }
    if (duration > 0.0) blackout(tick_s, duration, state);
  }
}

void LandingRun::on_tick(double tick_s) {
  track_near_miss(tick_s);
  inject_faults(tick_s);
  sim_s_ = tick_s;
  launch_.note_sim_time(sim_s_);
}

void LandingRun::poll_status(bool no_tick) {
  // twice a second while the program flies; once it has exited, the clock holds (below) until this
  // sees it, so at every pass that brought no tick: at 0.5 s that wait was up to a sixth of a run
  const double interval_s = launch_.programs_done() && no_tick ? 0.0 : 0.5;
  if (launch_.wall_s() - last_status_wall_s_ <= interval_s) return;
  last_status_wall_s_ = launch_.wall_s();
  SimConnection& api = launch_.api();
  if (const auto s = api.status(); s) {
    sim_s_ = s->value("time_s", sim_s_);
    launch_.note_sim_time(sim_s_);
    // the program exits 3 s after its landing and the clock holds then (pause_at): go on to the
    // 5 s on the deck, where the next armed pause holds it again (never the budget's own pause:
    // this poll runs on wall time, so a resume there made the end depend on whether a poll fell
    // between that pause and the budget check below: a run with a 40 s budget that landed at
    // 38.6 s ended at 40 s or, resumed, at 41.9 s)
    if (landed_s_ >= 0 && s->value("paused", false) &&
        sim_s_ < landed_s_ + kStayOnDeck_s - kPauseSlack_s &&
        sim_s_ < o_.start_time_s + o_.budget_s - kPauseSlack_s)
      (void)api.resume();
  }
}

bool LandingRun::run_over() {
  // scored: still on the deck 5 s after touchdown
  if (on_deck_long_enough(sim_s_)) return true;
  if (launch_.programs_done() && landed_s_ < 0) return true;
  if (launch::interrupted()) return true;
  if (sim_s_ >= o_.start_time_s + o_.budget_s - kPauseSlack_s) {
    launch_.say("mbzirc2017-run: sim-time budget spent");
    return true;
  }
  std::string failure;
  if (launch::run_must_end(launch_, "mbzirc2017-run", o_.wall_limit_s, &failure)) {
    if (!failure.empty()) fail(failure);
    return true;
  }
  return false;
}

// 3. follow the program and the event stream until it has landed (and 5 s more), it gave up, or
// the budget is spent
void LandingRun::follow() {
  SimConnection& api = launch_.api();
  while (!failed_) {
    launch_.pump(ticks_.empty() ? 50 : 0);
    for (const SimMessage& m : api.take_messages()) {
      if (m.kind() == "sim_event") on_sim_event(m.json);
    }
    // the fault injector: at each tick, act on the program's state changes stamped before it
    // (requests below may read further ticks into ticks_: they wait for the next pass)
    const std::vector<std::pair<std::int64_t, double>> due = std::move(ticks_);
    ticks_.clear();
    for (const auto& [tick, tick_s] : due) {
      on_tick(tick_s);
      // the first tick 5 s after touchdown ends the run: it is not answered, so the clock stays
      // at it, and is paused there, before the launcher leaves the lockstep below. (Answered, the
      // clock went on towards the armed pause_at while the leave was on its way, and where it
      // stopped, 4 ms apart, depended on which came first: one run of a 100-seed sweep ended at
      // 44.204 s, its twin at 44.200 s.)
      if (on_deck_long_enough(tick_s)) break;
      if (!api.done(tick)) fail("the fault injector's done was refused");
    }
    poll_status(due.empty());
    if (run_over()) break;
  }
}

void LandingRun::finish() {
  SimConnection& api = launch_.api();
  // Landed and 5 s on: the clock is held at that tick (unanswered). Pause it there before leaving.
  // Leaving alone let the end depend on a race between two sockets: the ground-truth recorder,
  // handling the same tick on its own connection, either still saw this client (answered, and the
  // clock went on to the armed pause_at 8 ms later) or already saw it gone (left too, and the
  // empty-lockstep pause held the clock at the tick): seed 10 of a 100-seed sweep ended at 44.4 s
  // on SLURM and 44.408 s locally.
  if (on_deck_long_enough(sim_s_)) (void)api.pause();
  (void)api.lockstep_leave();
  // the clock holds by itself at the end (pause_at): score once it does (interrupted: as it
  // stands)
  for (const double until_s = launch_.wall_s() + 10.0;
       !failed_ && !launch::interrupted() && launch_.wall_s() < until_s; launch_.pump(10)) {
    const auto st = api.status();
    if (!st || st->value("paused", false)) break;
  }
  if (!o_.events_path.empty()) {
    if (const auto ev = api.request({{"op", "events"}}); ev) {
      std::ofstream f(o_.events_path);
      for (const Json& e : ev->at("events")) f << e.dump() << "\n";
    }
  }
  score();
}

// 4. score from ground truth
void LandingRun::score() {
  SimConnection& api = launch_.api();
  if (const auto t = api.truck(); t) {
    end_sim_s_ = t->value("time_s", 0.0);
    for (const Json& truck : t->at("trucks")) {
      for (const Json& c : truck.value("carried_vehicles", Json::array()))
        stayed_on_deck_ = stayed_on_deck_ || c == 0;
    }
  }
  for (const SimMessage& m : api.take_messages()) {
    if (m.kind() == "sim_event" && m.json.value("type", "") == "crash") {
      crashes_.push_back(m.json.value("vehicle_name", "") + ": " + m.json.value("detail", ""));
    }
  }
  stayed_on_deck_ = stayed_on_deck_ && on_deck_long_enough(end_sim_s_);
}

void LandingRun::clean_up() const {
  if (world_ != o_.world) std::remove(world_.c_str());
}

bool LandingRun::success() const {
  return !failed_ && !launch::interrupted() && landed_s_ >= 0 && stayed_on_deck_ &&
         crashes_.empty();
}

void LandingRun::print_summary(bool success) const {
  const bool landed = landed_s_ >= 0;
  std::printf("==== MBZIRC 2017 landing on the moving truck, seed %llu ====\n",
              static_cast<unsigned long long>(o_.seed));
  std::printf(
      "landed on the deck: %s%s\n", landed ? "yes" : "no",
      landed ? (stayed_on_deck_ ? " (still on it 5 s later)" : " (NOT on it 5 s later)") : "");
  if (mission_s() >= 0) {
    std::printf("take-off to touchdown: %.1f s sim (take-off t=%.1f s, touchdown t=%.1f s)\n",
                mission_s(), takeoff_s_, landed_s_);
    std::printf("relative speed at touchdown: %.2f m/s; distance from the marker centre: %.2f m\n",
                relative_speed_m_s_, marker_distance_m_);
  } else {
    std::printf("take-off to touchdown: n/a\n");
  }
  // the near misses (ground truth at every tick) and where on the eight
  const std::optional<double> cab_clearance = near_miss_->min_clearance_m("cab");
  const std::optional<double> deck_margin = near_miss_->min_deck_edge_margin_m();
  std::printf(
      "start: t=%.1f s%s; truck at %.1f km/h; approach began on the %s, touchdown on the %s\n",
      o_.start_time_s,
      o_.start_phase ? (" (" + std::to_string(*o_.start_phase) + " of a lap)").c_str() : "",
      truck_kmh(), part_at_approach_.empty() ? "-" : part_at_approach_.c_str(),
      part_at_touchdown_.empty() ? "-" : part_at_touchdown_.c_str());
  std::printf(
      "near misses: cab clearance min %s m; skids to the deck's edges min %s m; %d climb-away(s); "
      "%d step(s) of the position estimate noticed\n",
      cab_clearance ? std::to_string(*cab_clearance).c_str() : "-",
      deck_margin ? std::to_string(*deck_margin).c_str() : "-", climb_aways_, estimate_steps_);
  std::printf("crashes: %s\n", crashes_.empty() ? "none" : "");
  for (const std::string& c : crashes_) std::printf("  %s\n", c.c_str());
  std::printf("sim time: %.1f s, wall time: %.1f s\n", end_sim_s_, launch_.wall_s());
  std::printf("video: %s\n", o_.record.empty() ? "none" : o_.record.c_str());
  if (!vision_log_.empty()) {
    std::printf("vision log: %s (uavsim-videolog-export %s --mp4 FILE)\n", vision_log_.c_str(),
                vision_log_.c_str());
  }
  if (!o_.run_dir.empty()) {
    std::printf("run directory: %s (%llu ground-truth rows; plots: scripts/plot_run.py %s)\n",
                o_.run_dir.c_str(), static_cast<unsigned long long>(launch_.truth_rows()),
                o_.run_dir.c_str());
  }
  std::printf("RESULT: %s%s\n", success ? "SUCCESS" : "FAILURE",
              launch::interrupted() ? " (interrupted)" : "");
  std::fflush(stdout);
}

Json LandingRun::summary_json(bool success) const {
  const std::optional<double> cab_clearance = near_miss_->min_clearance_m("cab");
  const std::optional<double> deck_margin = near_miss_->min_deck_edge_margin_m();
  Json summary;
  summary["mission"] = "mbzirc2017";
  summary["run_dir"] = o_.run_dir;
  summary["video"] = o_.record;
  summary["vision_log"] = vision_log_;
  summary["seed"] = o_.seed;
  summary["truck_speed_kmh"] = truck_kmh();
  summary["start_time_s"] = o_.start_time_s;
  summary["start_phase"] = o_.start_phase ? Json(*o_.start_phase) : Json(nullptr);
  summary["eight_part_at_approach"] =
      part_at_approach_.empty() ? Json(nullptr) : Json(part_at_approach_);
  summary["eight_part_at_touchdown"] =
      part_at_touchdown_.empty() ? Json(nullptr) : Json(part_at_touchdown_);
  Json clearance = Json::object();
  for (const auto& [part, m] : near_miss_->min_clearance_m()) clearance[part] = m;
  summary["min_clearance_m"] = clearance;
  summary["min_cab_clearance_m"] = cab_clearance ? Json(*cab_clearance) : Json(nullptr);
  summary["min_deck_edge_margin_m"] = deck_margin ? Json(*deck_margin) : Json(nullptr);
  summary["truck_contacts"] = truck_contacts(crashes_);
  summary["climb_aways"] = climb_aways_;
  summary["estimate_steps"] = estimate_steps_;
  Json random_blackouts = Json::array();
  for (const auto& [at_s, duration_s] : blackouts_)
    random_blackouts.push_back({{"at_s", at_s}, {"duration_s", duration_s}});
  summary["random_blackouts"] = random_blackouts;
  summary["landed"] = landed_s_ >= 0;
  summary["stayed_on_deck"] = stayed_on_deck_;
  summary["takeoff_time_s"] = takeoff_s_;
  summary["touchdown_time_s"] = landed_s_;
  summary["mission_time_s"] = mission_s();
  summary["relative_speed_m_s"] = relative_speed_m_s_;
  summary["marker_distance_m"] = marker_distance_m_;
  summary["crashes"] = crashes_;
  summary["states"] = states_;
  summary["blackout_first_pass_at_s"] = first_blackout_s_;
  summary["blackout_approach_at_s"] = approach_blackout_s_;
  summary["lose_low_off_centre_at_s"] = lose_low_at_s_;
  summary["sim_time_s"] = end_sim_s_;
  summary["wall_time_s"] = launch_.wall_s();
  summary["success"] = success;
  return summary;
}

}  // namespace uavsim::missions::mbzirc2017
