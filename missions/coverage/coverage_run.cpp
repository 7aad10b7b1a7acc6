#include "coverage_run.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iterator>
#include <limits>
#include <regex>
#include <sstream>
#include <tuple>

#include "uavsim/client/sim_connection.hpp"
#include "uavsim/common/fmt.hpp"
#include "uavsim/common/install_paths.hpp"
#include "uavsim/launch/run_options.hpp"

namespace uavsim::missions::coverage {
namespace {

using client::Result;
using client::SimConnection;
using client::SimMessage;
using Json = nlohmann::json;
using WallClock = std::chrono::steady_clock;
using common::fmt;

constexpr double kLauncherTick_s = 1.0;    // the launcher's lockstep period (sampling, kills)
constexpr double kFailurePeriod_s = 10.0;  // failures are drawn every 10 s (thesis 4.3)
constexpr double kAgentPeriod_s = 0.05;    // the agents' lockstep period (20 Hz)
constexpr int kStationId = 255;

}  // namespace

CoverageRun::CoverageRun(const CoverageRunOptions& o, const CoverageConfig& config,
                         const WorldSpec& spec)
    : o_(o),
      config_(config),
      spec_(spec),
      stripes_(config.stripe_count()),
      wall_start_(WallClock::now()),
      recovery_(stripes_, config.width_y_m, config.length_x_m),
      failure_rng_(o.seed ^ 0x9e3779b97f4a7c15ULL) {}

bool CoverageRun::make_world() {
  std::string dir_template = (std::filesystem::temp_directory_path() / "coverage-run-XXXXXX");
  if (mkdtemp(dir_template.data()) == nullptr) {
    fail("cannot make a temporary directory");
    return false;
  }
  dir_ = dir_template;
  world_path_ = (dir_ / "coverage.xml").string();
  std::ofstream(world_path_) << coverage_world_xml(spec_);
  if (!o_.keep_world.empty()) std::ofstream(o_.keep_world) << coverage_world_xml(spec_);
  return true;
}

bool CoverageRun::on_agent_line(const std::string& line) {
  if (line.rfind("APD ", 0) == 0) {
    if (auto r = decode_apd_report(line, stripes_)) {
      if (r->agent == kStationId) {
        recovery_.station_report(r->apd);
      } else {
        recovery_.agent_report(r->agent, r->apd);
      }
      apd_[r->agent] = std::move(*r);
    }
    return false;  // not printed: long
  }
  static const std::regex state_re(R"(^agent (\d+) t=\S+ state (.+) leader (-?\d+)$)");
  static const std::regex complete_re(R"(^agent (\d+) t=(\S+) mission complete)");
  static const std::regex recall_re(R"(^agent \d+ t=\S+ .*\(recall: round \d+\))");
  static const std::regex times_re(R"(^agent (\d+) t=\S+ time in states:(.*)$)");
  static const std::regex over_re(R"(^agent (\d+) t=\S+ over: )");
  std::smatch m;
  if (std::regex_search(line, m, state_re)) {
    const int id = std::stoi(m[1]);
    state_[id] = m[2];
    leader_of_[id] = std::stoi(m[3]);
    if (m[2] == "Querying" || m[2] == "Deploying" || m[2] == "Running" || m[2] == "Waiting")
      leaders_.insert(id);
  } else if (std::regex_search(line, m, complete_re)) {
    completed_by_ = std::stoi(m[1]);
    const double t = std::strtod(m[2].str().c_str(), nullptr);
    if (std::isfinite(t) && t >= 0.0) completed_at_s_ = t;
  } else if (std::regex_search(line, m, recall_re)) {
    ++recalls_;
  } else if (std::regex_search(line, m, times_re)) {
    auto& times = agent_time_in_state_s_[std::stoi(m[1])];
    times.fill(0.0);
    std::istringstream in(m[2].str());
    double v = 0.0;
    for (int k = 0; k < kAgentStateCount && in >> v; ++k) {
      if (std::isfinite(v) && v >= 0.0) times[static_cast<size_t>(k)] = v;
    }
  } else if (std::regex_search(line, m, over_re)) {
    over_.insert(std::stoi(m[1]));
  }
  return true;
}

// applies what is stamped before t_s (everything: +infinity), in order
void CoverageRun::apply_pending(double t_s) {
  std::sort(pending_.begin(), pending_.end(), [](const Stamped& a, const Stamped& b) {
    return std::tie(a.t_s, a.source, a.arrival) < std::tie(b.t_s, b.source, b.arrival);
  });
  size_t n = 0;
  while (n < pending_.size() && pending_[n].t_s < t_s - 1e-9) ++n;
  std::vector<Stamped> due(std::make_move_iterator(pending_.begin()),
                           std::make_move_iterator(pending_.begin() + static_cast<long>(n)));
  pending_.erase(pending_.begin(), pending_.begin() + static_cast<long>(n));
  for (Stamped& s : due) s.apply();
}

// a program's line: applied in order if it carries a sim time ("agent N t=T ...", an APD
// report), at once otherwise (it is only printed)
void CoverageRun::on_program_line(const std::string& child, const std::string& line) {
  static const std::regex stamp_re(R"(^agent (\d+) t=(\S+) )");
  std::smatch m;
  int source = -1;
  double t_s = 0.0;
  if (line.rfind("APD ", 0) == 0) {
    if (auto r = decode_apd_report(line, stripes_)) {
      source = r->agent;
      t_s = r->time_s;
    }
  } else if (std::regex_search(line, m, stamp_re)) {
    source = std::stoi(m[1]);
    t_s = std::strtod(m[2].str().c_str(), nullptr);
  }
  auto apply = [this, child, line] {
    if (on_agent_line(line)) say("[" + child + "] " + line);
  };
  if (source >= 0 && std::isfinite(t_s)) {
    stamp(t_s, source, apply);
  } else {
    apply();
  }
}

AreaParts CoverageRun::held_apd() const {
  AreaParts held(stripes_);
  for (const auto& [id, r] : apd_) {
    if (!killed_.count(id) && !crashed_.count(id)) held.merge(r.apd);
  }
  return held;
}

// 2. the server, on ephemeral ports, as fast as possible; the lines of every program go through
// on_agent_line (the launcher's own printing is off: APD reports are not for people)
void CoverageRun::start(Launcher& launch) {
  launch_ = &launch;
  launch.on_exit([this](const launch::ProgramEnd& e) {
    const auto it = agents_of_.find(e.name);
    if (it == agents_of_.end() || !e.abnormal()) return;
    for (int i = it->second.first; i <= it->second.second; ++i) {
      if (killed_.count(i) || crashed_.count(i)) continue;
      if (launch_->api().request({{"op", "kill_vehicle"},
                                  {"vehicle", i},
                                  {"reason", "coverage-run: its agent program " + e.how}}))
        mark_failed(i, killed_, sim_s_);
    }
  });
  launch.on_line([this](const std::string& child, const std::string& line) {
    if (child == "server") {
      if (line.find(": MAVLink on tcp:") == std::string::npos) say("[server] " + line);
    } else {
      on_program_line(child, line);
    }
  });
  if (auto r = launch::start_run_server(launch, server_options(), server_args()); !r) {
    fail("the server did not start: " + r.message());
  }
}

launch::RunOptions CoverageRun::server_options() const {
  launch::RunOptions server = o_;
  server.world = world_path_;
  return server;
}

std::vector<std::string> CoverageRun::server_args() const {
  // cameras only for the video: the world's overview camera, which the agents never see
  std::vector<std::string> args{"--models-dir", o_.models_dir, "--radio-backend", o_.radio_backend};
  if (o_.record.empty()) args.push_back("--no-cameras");
  return args;
}

int CoverageRun::run_floor(Launcher& launch) {
  // the agents see no camera: nothing to render beside the video's, if one is recorded
  return launch::run_floor(launch, "coverage", server_options(), server_args(), "");
}

// 4. the optimised variant: the ground station, its link ports, the server's relay in front of
// each vehicle's link (seed 6.3), impaired as asked
void CoverageRun::start_ground_station(const std::string& lockstep) {
  SimConnection& api = launch_->api();
  static const std::regex port_re(R"(^gcs: uav(\d+) link on udp:[0-9.]+:(\d+)$)");
  launch_->on_line([this](const std::string& child, const std::string& line) {
    std::smatch m;
    if (child == "gcs" && std::regex_search(line, m, port_re))
      station_port_[std::stoi(m[1])] = std::stoi(m[2]);
  });
  if (auto g = launch_->spawn("gcs",
                              {o_.gcs_program, "--uavs", std::to_string(o_.agents), "--area",
                               fmt("%.3f", o_.length_x_m) + "x" + fmt("%.3f", o_.width_y_m)},
                              {lockstep});
      !g) {
    fail(g.message());
  }
  ++processes_;
  while (!failed_ && static_cast<int>(station_port_.size()) < o_.agents &&
         launch_->wall_s() < 60.0 && !launch_->programs_done()) {
    launch_->pump(100);
  }
  if (!failed_ && static_cast<int>(station_port_.size()) < o_.agents)
    fail("the ground station did not start");
  for (int i = 0; i < o_.agents && !failed_; ++i) {
    Result<Json> g = api.request({{"op", "gcs_link_open"},
                                  {"vehicle", i},
                                  {"gcs_target_host", "127.0.0.1"},
                                  {"gcs_target_port", station_port_[i]}});
    if (g) gcs_uav_port_[static_cast<size_t>(i)] = g->value("uav_port", 0);
    if (g && o_.gcs_loss > 0.0)
      g = api.request({{"op", "gcs_link_impair"}, {"vehicle", i}, {"loss", o_.gcs_loss}});
    if (!g) fail("GCS link of vehicle " + std::to_string(i) + ": " + g.message());
  }
}

// 5. the agent programs, per_process agents each
void CoverageRun::start_agents(const std::string& lockstep) {
  for (int first = 0; first < o_.agents && !failed_; first += o_.per_process) {
    const int last = std::min(o_.agents, first + o_.per_process) - 1;
    std::string ports, gcs_ports;
    for (int i = first; i <= last; ++i) {
      const int port = launch_->mavlink_port("uav" + std::to_string(i));
      if (port == 0) {
        fail("no MAVLink port for uav" + std::to_string(i));
        break;
      }
      // appended piece by piece: GCC 12 warns (-Wrestrict, a false positive) on ("," + string)
      ports += ports.empty() ? "" : ",";
      ports += std::to_string(port);
      gcs_ports += gcs_ports.empty() ? "" : ",";
      gcs_ports += std::to_string(gcs_uav_port_[static_cast<size_t>(i)]);
    }
    const std::string name = first == last
                                 ? "agent" + std::to_string(first)
                                 : "agents" + std::to_string(first) + "-" + std::to_string(last);
    std::vector<std::string> args{o_.agent,
                                  "--vehicles",
                                  std::to_string(first) + "-" + std::to_string(last),
                                  "--area",
                                  fmt("%.3f", o_.length_x_m) + "x" + fmt("%.3f", o_.width_y_m),
                                  "--mavlink-ports",
                                  ports,
                                  "--status-period",
                                  fmt("%.3f", o_.agent_status_s)};
    if (o_.gcs) args.insert(args.end(), {"--gcs-ports", gcs_ports});
    if (o_.pipelined && !o_.gcs) args.push_back("--pipelined");
    if (o_.thesis_flocking) args.push_back("--thesis-flocking");
    agents_of_[name] = {first, last};
    if (auto s = launch_->spawn(name, args, {lockstep}); !s) {
      fail(s.message());
    }
    ++processes_;
  }
}

double CoverageRun::send_spread_s() const {
  if (o_.radio_backend != "ns3" || o_.radio_tdma_slot_s > 0.0) return 0.0;
  if (o_.radio_send_spread_s >= 0.0) return o_.radio_send_spread_s;
  // the agents' programs run on clocks of their own, not at the server's tick: on 802.11 (DCF sends
  // at once on an idle medium) their frames enter over one tick, as theirs would; 802.15.4's
  // CSMA-CA draws an initial backoff of its own
  return o_.radio_technology == "802.11" ? kAgentPeriod_s : 0.0;
}

void CoverageRun::set_up() {
  SimConnection& api = launch_->api();
  // 3. hold the clock at t = 0 with this seed; the radio; the events; the launcher's ticks
  Result<Json> r = api.pause();
  if (r) r = api.reset(o_.seed);
  Json radio = {{"op", "radio_config"},
                {"model", "range"},
                {"range_m", o_.radio_range_m},
                {"loss", o_.radio_loss}};
  if (o_.radio_backend == "ns3") {
    radio["technology"] = o_.radio_technology;
    radio["send_spread_s"] = send_spread_s();
  }
  if (o_.radio_tdma_slot_s > 0) {
    radio["tdma"] = true;
    radio["slot_s"] = o_.radio_tdma_slot_s;
    radio["period_s"] = 1.0;
  }
  if (r) r = api.request(radio);
  if (r) r = api.subscribe_events();
  if (r) r = api.lockstep_join(kLauncherTick_s, 120.0);
  if (!r) fail("setting up the run: " + r.message());

  const std::string lockstep = launch_->lockstep_env(kAgentPeriod_s);
  gcs_uav_port_.assign(static_cast<size_t>(o_.agents), 0);
  if (o_.gcs) start_ground_station(lockstep);
  start_agents(lockstep);
  // 6. once every program has joined the lockstep, let the clock go
  if (failed_) return;
  if (auto w = launch_->wait_lockstep_clients(processes_ + 1, 120.0); !w) {
    fail("the agent programs did not join the lockstep: " + w.message());
  } else if (!api.resume()) {
    fail("resume refused");
  } else {
    char buf[256];
    std::snprintf(
        buf, sizeof buf,
        "coverage-run: %d agents, area %.0f x %.0f m (%d stripes), failure p %.4f, "
        "radio %s%s%s range %.0f m loss %.2f, seed %llu%s",
        o_.agents, o_.length_x_m, o_.width_y_m, stripes_, o_.failure_prob, o_.radio_backend.c_str(),
        o_.radio_backend == "ns3" ? (" " + o_.radio_technology).c_str() : "",
        o_.radio_tdma_slot_s > 0 ? " tdma" : "", o_.radio_range_m, o_.radio_loss,
        static_cast<unsigned long long>(o_.seed), o_.gcs ? ", with a ground station" : "");
    say(buf);
  }
}

void CoverageRun::end_at_tick() {
  SimConnection& api = launch_->api();
  if (auto v = api.request({{"op", "vehicles"}})) {
    sim_s_ = v->value("time_s", sim_s_);
    for (const Json& x : (*v)["vehicles"]) vehicles_end_.push_back(x);
  }
  // what the radio channel did: frames sent, refused, delivered, lost
  if (auto r = api.request({{"op", "radio_stats"}})) {
    Json totals = {{"backend", r->value("backend", "")},
                   {"max_frame_bytes", r->value("max_frame_bytes", 0)}};
    auto sum = [&totals](const Json& rows, std::initializer_list<const char*> fields) {
      for (const char* f : fields) {
        uint64_t n = 0;
        for (const Json& row : rows) n += row.value(f, uint64_t{0});
        totals[f] = n;
      }
    };
    sum((*r)["vehicles"], {"transmitted", "refused", "channel_access_failures"});
    sum((*r)["links"], {"sent", "delivered", "lost", "collided", "out_of_range", "no_ack"});
    radio_end_ = std::move(totals);
  }
  // what the relay did to each GCS link
  for (int i = 0; o_.gcs && i < o_.agents; ++i) {
    if (auto g = api.request({{"op", "gcs_link_stats"}, {"vehicle", i}})) gcs_links_.push_back(*g);
  }
  (void)api.lockstep_leave();
  ended_ = true;
}

void CoverageRun::on_sim_event(const Json& e) {
  const std::string type = e.value("type", "");
  const double t = e.value("time", 0.0);
  const int veh = e.value("vehicle", -1);
  stamp(t, -1,
        [this, type, t, veh, name = e.value("vehicle_name", ""), detail = e.value("detail", "")] {
          if (type == "takeoff")
            first_takeoff_s_ = first_takeoff_s_ < 0 ? t : std::min(first_takeoff_s_, t);
          if (type == "touchdown" && !killed_.count(veh))
            last_touchdown_s_ = std::max(last_touchdown_s_, t);
          if (type == "vehicle_killed") mark_failed(veh, killed_, t);
          if (type == "crash" && !killed_.count(veh)) mark_failed(veh, crashed_, t);
          if (type == "crash" || type == "vehicle_killed")
            say("[event] t=" + fmt("%.2f", t) + " " + type + " " + name + " " + detail);
        });
}

std::vector<int> CoverageRun::sample_truth() {
  std::vector<int> flying;
  if (auto v = launch_->api().request({{"op", "vehicles"}})) {
    for (const Json& x : (*v)["vehicles"]) {
      const int i = x.value("index", -1);
      const Json p = x["position_enu_m"];
      const Eigen::Vector3d pos(p[0].get<double>(), p[1].get<double>(), p[2].get<double>());
      if (last_pos_.count(i)) distance_m_[i] += (pos - last_pos_[i]).head<2>().norm();
      last_pos_[i] = pos;
      // energy up to the disarm (a landed quad's boards would be switched off)
      const bool armed = x.value("armed", false);
      if (armed || !was_armed_[i]) energy_mah_[i] = x.value("battery_used_mah", 0.0);
      was_armed_[i] = was_armed_[i] || armed;
      if (armed && !x.value("crashed", false) && !x.value("on_ground", true)) flying.push_back(i);
    }
  }
  return flying;
}

// failures: scheduled kills, then every 10 s a draw per flying agent; and the ground station's
// links cut (every datagram dropped from then on)
void CoverageRun::inject_failures(double t, const std::vector<int>& flying) {
  SimConnection& api = launch_->api();
  std::vector<int> to_kill;
  while (next_kill_ < o_.kills.size() && o_.kills[next_kill_].first <= t + 1e-9)
    to_kill.push_back(o_.kills[next_kill_++].second);
  const long k = std::lround(t / kFailurePeriod_s);
  if (o_.failure_prob > 0 && k > 0 && std::abs(t - k * kFailurePeriod_s) < 1e-6) {
    for (int i : flying) {
      if (uniform_(failure_rng_) < o_.failure_prob) to_kill.push_back(i);
    }
  }
  if (o_.gcs && !gcs_cut_ && o_.gcs_cut_s >= 0.0 && t + 1e-9 >= o_.gcs_cut_s) {
    gcs_cut_ = true;
    for (int i = 0; i < o_.agents; ++i) {
      if (!api.request({{"op", "gcs_link_impair"}, {"vehicle", i}, {"outage_s", 1e6}}))
        fail("cutting the GCS link of vehicle " + std::to_string(i));
    }
    say("coverage-run: t=" + fmt("%.1f", t) + " GCS links cut");
  }
  for (int i : to_kill) {
    if (killed_.count(i)) continue;
    if (api.request({{"op", "kill_vehicle"},
                     {"vehicle", i},
                     {"reason", "coverage-run: injected failure"}})) {
      mark_failed(i, killed_, t);
      say("coverage-run: t=" + fmt("%.1f", t) + " killed agent " + std::to_string(i));
    }
  }
}

void CoverageRun::print_progress(double t) {
  std::map<std::string, int> counts;
  int leader = -1;
  for (const auto& [id, s] : state_) {
    if (killed_.count(id)) continue;
    ++counts[s];
    if (s == "Querying" || s == "Deploying" || s == "Running" || s == "Waiting")
      leader = leader < 0 ? id : std::min(leader, id);
  }
  std::string line = "coverage-run: t=" + fmt("%.0f", t) + " s coverage " +
                     fmt("%.1f", 100.0 * held_fraction()) + " % leader " +
                     (leader < 0 ? std::string("-") : std::to_string(leader)) + " |";
  for (const auto& [s, n] : counts) line += " " + s + " " + std::to_string(n);
  line += " | wall " + fmt("%.1f", wall_s()) + " s";
  say(line);
}

void CoverageRun::on_tick(const Json& e) {
  SimConnection& api = launch_->api();
  const double t = e.value("time", 0.0);
  sim_s_ = t;
  // what the programs printed before this tick has arrived: read it, apply it in order
  launch_->pump(0);
  apply_pending(t);
  launch_->note_sim_time(t);
  inject_failures(t, sample_truth());
  // the video's coverage counter: what the surviving agents' reports hold, as scored
  if (!o_.record.empty()) {
    (void)api.request({{"op", "overlay_counter"},
                       {"name", "coverage"},
                       {"text", "coverage " + fmt("%.1f", 100.0 * held_fraction()) + " %"}});
  }
  if (t + 1e-9 >= next_progress_s_) {
    next_progress_s_ += o_.progress_period_s;
    print_progress(t);
  }
  if (static_cast<int>(over_.size()) >= o_.agents || t + 1e-9 >= o_.budget_s) {
    end_at_tick();
    return;
  }
  if (!api.done(e.value("tick", std::int64_t{0}))) fail("the launcher's done was refused");
}

bool CoverageRun::run_over() {
  // the server first: its death ends the agents too, and that is the harness's failure
  if (launch_->server_exited() || !launch_->api().connected()) {
    fail(launch_->server_end());
    return true;
  }
  if (launch_->programs_done(o_.gcs ? "gcs" : "")) return true;
  if (launch::interrupted()) return true;
  if (!launch_->records_error().empty()) {
    fail("the run's records cannot be written: " + launch_->records_error());
    return true;
  }
  if (ended_ && sim_s_ + 1e-9 >= o_.budget_s) {
    say("coverage-run: sim-time budget spent");
    return true;
  }
  if (wall_s() > o_.wall_limit_s) {
    say("coverage-run: wall-clock limit reached");
    return true;
  }
  return false;
}

// 7. follow the run: the launcher's ticks (ground truth samples, kills), events, output
void CoverageRun::follow() {
  SimConnection& api = launch_->api();
  next_progress_s_ = o_.progress_period_s;
  while (!failed_) {
    launch_->pump(50);
    for (const SimMessage& msg : api.take_messages()) {
      const std::string ev = msg.kind();
      if (ev == "sim_event") {
        on_sim_event(msg.json);
      } else if (ev == "tick" && !ended_) {
        on_tick(msg.json);
      }
    }
    if (run_over()) break;
  }
  // 8. score from ground truth, where the run did not reach its end (the programs gone before
  // it, interrupted, the wall-clock limit): as the clock stands
  if (!failed_ && !ended_) end_at_tick();
}

Json CoverageRun::gaps() const {
  constexpr std::size_t kGapsListed = 20;
  Json gaps = Json::array();
  for (const CoverageGap& g : coverage_gaps(held_apd(), config_.width_y_m, kGapsListed))
    gaps.push_back({g.stripe, g.from_m, g.to_m});
  return gaps;
}

CoverageScore CoverageRun::finish() {
  std::filesystem::remove_all(dir_);
  apply_pending(std::numeric_limits<double>::infinity());  // the programs' last lines
  // each vehicle as ground truth left it, then the tally (run_score.hpp)
  std::vector<VehicleOutcome> outcomes;
  Json per_agent = Json::array();
  for (const Json& x : vehicles_end_) {
    const int i = x.value("index", -1);
    const bool dead = killed_.count(i) || crashed_.count(i) || x.value("crashed", false);
    const bool down = x.value("on_ground", false) && !x.value("armed", true);
    const double mah = energy_mah_[i];
    outcomes.push_back({dead, down, mah, distance_m_[i]});
    Json entry = {
        {"agent", i},
        {"failed", dead},
        {"landed", down && !dead},
        {"state", state_.count(i) ? state_[i] : ""},
        {"energy_mah", mah},
        {"held_fraction", apd_.count(i) ? apd_[i].apd.covered_fraction(config_.width_y_m) : 0.0},
        {"distance_m", distance_m_[i]}};
    if (auto f = failure_at_.find(i); f != failure_at_.end()) {
      entry["failed_at_s"] = f->second.first;
      entry["lost_fraction"] = f->second.second;
    }
    per_agent.push_back(std::move(entry));
  }
  CoverageScore s;
  static_cast<RunTally&>(s) =
      tally_run(outcomes, {first_takeoff_s_, last_touchdown_s_, completed_at_s_}, held_fraction(),
                !failed_ && !launch::interrupted());
  s.per_agent = std::move(per_agent);
  for (const auto& [id, times] : agent_time_in_state_s_) {
    for (size_t k = 0; k < times.size(); ++k) s.time_in_state_s[k] += times[k];
  }
  s.gcs_fraction =
      apd_.count(kStationId) ? apd_[kStationId].apd.covered_fraction(config_.width_y_m) : 0.0;
  s.gaps = gaps();
  return s;
}

// fig. 4.9: share of the agents' time in each state, Going Home, Landed and Failed left out
void CoverageRun::print_time_in_states(
    const std::array<double, kAgentStateCount>& time_in_state_s) const {
  double total = 0.0;
  for (int k = 0; k < kAgentStateCount; ++k) {
    const auto st = static_cast<AgentState>(k);
    if (st != AgentState::kGoingHome && st != AgentState::kLanded && st != AgentState::kFailed)
      total += time_in_state_s[static_cast<size_t>(k)];
  }
  if (total <= 0.0) return;
  std::printf("time in states (fig. 4.9):");
  for (int k = 0; k < kAgentStateCount; ++k) {
    const auto st = static_cast<AgentState>(k);
    if (st == AgentState::kGoingHome || st == AgentState::kLanded || st == AgentState::kFailed)
      continue;
    std::printf(" %s %.1f %%", agent_state_name(st),
                100.0 * time_in_state_s[static_cast<size_t>(k)] / total);
  }
  std::printf("\n");
}

void CoverageRun::print_radio() const {
  if (!radio_end_.contains("transmitted")) return;
  std::printf(
      "radio (%s, frames of at most %d bytes): %llu frames sent, %llu refused, %llu "
      "channel-access "
      "failures; %llu delivered, %llu lost\n",
      radio_end_["backend"].get<std::string>().c_str(), radio_end_["max_frame_bytes"].get<int>(),
      static_cast<unsigned long long>(radio_end_["transmitted"].get<uint64_t>()),
      static_cast<unsigned long long>(radio_end_["refused"].get<uint64_t>()),
      static_cast<unsigned long long>(radio_end_["channel_access_failures"].get<uint64_t>()),
      static_cast<unsigned long long>(radio_end_["delivered"].get<uint64_t>()),
      static_cast<unsigned long long>(radio_end_["lost"].get<uint64_t>()));
}

void CoverageRun::print_summary(const CoverageScore& s) {
  std::printf("==== coverage flock: %d agents, %.0f x %.0f m, failure p %.4f, seed %llu ====\n",
              o_.agents, o_.length_x_m, o_.width_y_m, o_.failure_prob,
              static_cast<unsigned long long>(o_.seed));
  std::printf("coverage held by surviving agents%s: %.2f %%\n",
              o_.gcs ? " and the ground station" : "", 100.0 * s.coverage);
  if (o_.gcs) std::printf("ground station holds: %.2f %%\n", 100.0 * s.gcs_fraction);
  if (s.mission_s >= 0)
    std::printf("mission time: %.1f s sim (first take-off %.1f s, last touchdown %.1f s)\n",
                s.mission_s, first_takeoff_s_, last_touchdown_s_);
  else
    std::printf("mission time: n/a\n");
  if (s.coverage_s >= 0)
    std::printf(
        "coverage complete: %.1f s after the first take-off (the leader's query at %.1f s); "
        "going home and landing: %.1f s\n",
        s.coverage_s, completed_at_s_, s.mission_s >= 0 ? s.mission_s - s.coverage_s : 0.0);
  std::printf("failed agents: %d of %d", s.failed, static_cast<int>(vehicles_end_.size()));
  for (int i : killed_) std::printf(" %d", i);
  for (int i : crashed_) std::printf(" %d(crash)", i);
  std::printf("\nlanded: %d of %d surviving\n", s.landed, s.survivors);
  if (!s.gaps.empty()) std::printf("gaps (stripe, y from, y to): %s\n", s.gaps.dump().c_str());
  std::printf("leaders: ");
  for (int i : leaders_) std::printf("%d ", i);
  std::printf("(completed by %d)", completed_by_);
  if (recalls_ > 0) std::printf(", %d recall(s) after losses on the way home", recalls_);
  std::printf("\n");
  print_time_in_states(s.time_in_state_s);
  if (!vehicles_end_.empty()) {
    std::printf("energy: %.0f mAh per agent (mean), %.0f mAh in all\n",
                s.energy_total / vehicles_end_.size(), s.energy_total);
    std::printf("distance flown: %.0f m in all, %.0f m per agent (mean)\n", s.distance_total,
                s.distance_total / vehicles_end_.size());
    if (s.failed > 0) {
      std::printf(
          "distance flown to recover lost data (table 4.3): %.0f m, %.3f %% of the distance "
          "flown; %.2f %% of the rectangle photographed again after it was lost, %.2f %% lost "
          "at the failures\n",
          recovery_.distance_m(),
          s.distance_total > 0 ? 100.0 * recovery_.distance_m() / s.distance_total : 0.0,
          100.0 * recovery_.recovered_fraction(), 100.0 * recovery_.lost_at_failures_fraction());
    }
  }
  print_radio();
  std::printf("sim time: %.1f s, wall time: %.1f s, speed %.1fx real time\n", sim_s_, wall_s(),
              wall_s() > 0 ? sim_s_ / wall_s() : 0.0);
  std::printf("video: %s\n", o_.record.empty() ? "none" : o_.record.c_str());
  if (!o_.run_dir.empty()) {
    std::printf("run directory: %s (%llu ground-truth rows; plots: scripts/plot_run.py %s)\n",
                o_.run_dir.c_str(), static_cast<unsigned long long>(launch_->truth_rows()),
                o_.run_dir.c_str());
  }
  std::printf("RESULT: %s coverage=%.4f mission_s=%.1f coverage_s=%.1f failed=%d landed=%d/%d%s\n",
              s.success ? "SUCCESS" : "FAILURE", s.coverage, s.mission_s, s.coverage_s, s.failed,
              s.landed, s.survivors, launch::interrupted() ? " (interrupted)" : "");
  std::fflush(stdout);
}

Json CoverageRun::summary_json(const CoverageScore& s) {
  Json summary;
  summary["mission"] = "coverage";
  summary["run_dir"] = o_.run_dir;
  summary["video"] = o_.record;
  summary["area_origin_m"] = {0.0, 0.0};
  summary["agents"] = o_.agents;
  summary["area_m"] = {o_.length_x_m, o_.width_y_m};
  summary["failure_prob"] = o_.failure_prob;
  summary["radio_range_m"] = o_.radio_range_m;
  summary["radio_loss"] = o_.radio_loss;
  summary["radio_backend"] = o_.radio_backend;
  summary["radio_tdma_slot_s"] = o_.radio_tdma_slot_s;
  summary["radio_technology"] = o_.radio_technology;
  summary["radio_send_spread_s"] = send_spread_s();
  summary["radio"] = radio_end_;
  summary["line_spacing_m"] = o_.line_spacing_m;
  summary["thesis_flocking"] = o_.thesis_flocking;
  summary["gcs"] = o_.gcs;
  if (o_.gcs) {
    summary["gcs_cut_s"] = o_.gcs_cut_s;
    summary["gcs_loss"] = o_.gcs_loss;
    summary["gcs_held_fraction"] = s.gcs_fraction;
    summary["gcs_links"] = gcs_links_;
  }
  summary["seed"] = o_.seed;
  summary["coverage"] = s.coverage;
  summary["mission_time_s"] = s.mission_s;
  summary["first_takeoff_s"] = first_takeoff_s_;
  summary["last_touchdown_s"] = last_touchdown_s_;
  summary["coverage_complete_s"] = s.coverage_s;
  summary["completed_at_s"] = completed_at_s_;
  summary["failed"] = s.failed;
  summary["killed"] = std::vector<int>(killed_.begin(), killed_.end());
  summary["crashed"] = std::vector<int>(crashed_.begin(), crashed_.end());
  summary["survivors"] = s.survivors;
  summary["gaps"] = s.gaps;
  Json states = Json::object();
  for (int k = 0; k < kAgentStateCount; ++k)
    states[agent_state_name(static_cast<AgentState>(k))] =
        s.time_in_state_s[static_cast<size_t>(k)];
  summary["time_in_state_s"] = states;
  summary["leaders"] = std::vector<int>(leaders_.begin(), leaders_.end());
  summary["completed_by"] = completed_by_;
  summary["recalls"] = recalls_;
  summary["landed"] = s.landed;
  summary["energy_mah_mean"] = vehicles_end_.empty() ? 0.0 : s.energy_total / vehicles_end_.size();
  summary["distance_m_total"] = s.distance_total;
  summary["recovery_distance_m"] = recovery_.distance_m();
  summary["recovered_fraction"] = recovery_.recovered_fraction();
  summary["lost_fraction_at_end"] = recovery_.lost_fraction();
  summary["lost_at_failures_fraction"] = recovery_.lost_at_failures_fraction();
  summary["per_agent"] = s.per_agent;
  // every agent's last APD report, the dead's and the station's (255) too: the coverage map
  summary["stripes"] = stripes_;
  Json apds = Json::array();
  for (const auto& [id, r] : apd_) {
    apds.push_back({{"agent", id},
                    {"failed", killed_.count(id) > 0 || crashed_.count(id) > 0},
                    {"report", encode_apd_report(id, r.time_s, r.apd)}});
  }
  summary["apd_reports"] = apds;
  summary["sim_time_s"] = sim_s_;
  summary["wall_time_s"] = wall_s();
  summary["success"] = s.success;
  return summary;
}

void CoverageRun::draw_map() const {
  if (o_.map_png.empty() || o_.json_path.empty() || o_.run_dir.find('\'') != std::string::npos)
    return;
  // the picture from the run directory (ground truth, summary); matplotlib's script
  const std::string plot = common::installed_or_built_program(
      "uavsim-plot", std::string(UAVSIM_SCRIPTS_DIR) + "/plot_run.py");
  const std::string cmd = "'" + plot + "' '" + o_.run_dir + "' --coverage-map '" + o_.map_png + "'";
  if (std::system(cmd.c_str()) != 0)
    std::fprintf(stderr, "coverage-run: the coverage map was not drawn (%s)\n", cmd.c_str());
}

}  // namespace uavsim::missions::coverage
