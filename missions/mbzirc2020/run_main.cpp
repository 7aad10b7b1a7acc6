// mbzirc2020-run: the whole MBZIRC 2020 balloon mission in the simulator, as on competition day
// (seed 7.2): uavsim-server on models/worlds/mbzirc2020.xml (seeded balloon positions, optional
// --record video), the ground station and one mission program per UAV, all on the server's lockstep
// clock at full speed. It prints the programs' progress and the simulator's events, then a summary
// scored from the sim API's ground truth (the programs never see it): balloons popped, mission
// time, crashes, the video.
//
// Exit status: 0 only when every balloon is popped and no vehicle crashed (other than one killed on
// purpose with --kill, Competition Day 2's failed UAV). 1: the mission fell short; 2: usage; 4: the
// harness failed.
#include <arpa/inet.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <poll.h>
#include <signal.h>
#include <spawn.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <regex>
#include <set>
#include <string>
#include <vector>

extern char** environ;

namespace {

using Json = nlohmann::json;
using Clock = std::chrono::steady_clock;

// a program installed beside this one (found through /proc/self/exe, so a PATH lookup works too)
std::string sibling(const char* argv0, const std::string& name) {
  char self[4096];
  const ssize_t n = readlink("/proc/self/exe", self, sizeof(self) - 1);
  std::string dir = n > 0 ? std::string(self, static_cast<size_t>(n)) : std::string(argv0);
  const size_t slash = dir.rfind('/');
  dir = slash == std::string::npos ? "." : dir.substr(0, slash);
  return dir + "/" + name;
}

// A child process with stdout and stderr on one pipe, read line by line without blocking.
struct Child {
  std::string name;
  pid_t pid = -1;
  int fd = -1;
  std::string buf;
  bool exited = false;
  int status = 0;

  bool spawn(const std::vector<std::string>& args, const std::vector<std::string>& env_extra) {
    int fds[2];
    if (pipe2(fds, O_CLOEXEC) != 0) return false;
    posix_spawn_file_actions_t fa;
    posix_spawn_file_actions_init(&fa);
    posix_spawn_file_actions_adddup2(&fa, fds[1], 1);
    posix_spawn_file_actions_adddup2(&fa, fds[1], 2);
    std::vector<std::string> env;
    for (char** e = environ; *e != nullptr; ++e) {
      if (std::strncmp(*e, "UAVSIM_LOCKSTEP=", 16) != 0) env.emplace_back(*e);
    }
    env.insert(env.end(), env_extra.begin(), env_extra.end());
    std::vector<char*> argv, envp;
    std::vector<std::string> a = args;
    for (auto& s : a) argv.push_back(s.data());
    argv.push_back(nullptr);
    for (auto& s : env) envp.push_back(s.data());
    envp.push_back(nullptr);
    const int rc = posix_spawn(&pid, argv[0], &fa, nullptr, argv.data(), envp.data());
    posix_spawn_file_actions_destroy(&fa);
    close(fds[1]);
    if (rc != 0) {
      close(fds[0]);
      pid = -1;
      return false;
    }
    fd = fds[0];
    fcntl(fd, F_SETFL, O_NONBLOCK);
    return true;
  }
  // reads what is there; complete lines out
  std::vector<std::string> read_lines() {
    std::vector<std::string> lines;
    if (fd < 0) return lines;
    char tmp[8192];
    for (;;) {
      const ssize_t n = read(fd, tmp, sizeof(tmp));
      if (n > 0) {
        buf.append(tmp, static_cast<size_t>(n));
        continue;
      }
      if (n == 0) {  // end of output
        close(fd);
        fd = -1;
        if (!buf.empty()) buf += '\n';
      }
      break;
    }
    size_t nl;
    while ((nl = buf.find('\n')) != std::string::npos) {
      lines.push_back(buf.substr(0, nl));
      buf.erase(0, nl + 1);
    }
    return lines;
  }
  bool reap() {
    if (pid <= 0 || exited) return exited;
    if (waitpid(pid, &status, WNOHANG) == pid) exited = true;
    return exited;
  }
  void stop(int sig, double wall_timeout_s) {
    if (pid <= 0 || reap()) return;
    kill(pid, sig);
    const auto end = Clock::now() + std::chrono::duration<double>(wall_timeout_s);
    while (!reap() && Clock::now() < end) usleep(10000);
    if (!exited) {
      kill(pid, SIGKILL);
      waitpid(pid, &status, 0);
      exited = true;
    }
  }
};

// Line-JSON client of the sim API: requests wait for their reply (by id); events are queued.
class Api {
 public:
  bool connect(int port) {
    fd_ = socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_port = htons(static_cast<uint16_t>(port));
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    if (::connect(fd_, reinterpret_cast<sockaddr*>(&a), sizeof(a)) != 0) return false;
    return read_one(10.0).has_value();  // hello
  }
  ~Api() {
    if (fd_ >= 0) close(fd_);
  }
  int fd() const { return fd_; }
  Json request(Json j, double wall_timeout_s = 30.0) {
    j["id"] = ++next_id_;
    const std::string line = j.dump() + "\n";
    if (send(fd_, line.data(), line.size(), MSG_NOSIGNAL) != static_cast<ssize_t>(line.size()))
      return Json();
    const auto end = Clock::now() + std::chrono::duration<double>(wall_timeout_s);
    while (Clock::now() < end) {
      auto m = read_one(std::chrono::duration<double>(end - Clock::now()).count());
      if (!m) return Json();
      if (m->contains("ok") && m->value("id", -1) == next_id_) return *m;
      if (m->contains("event")) events_.push_back(*m);
    }
    return Json();
  }
  // events already read plus whatever is waiting now
  std::vector<Json> take_events() {
    for (;;) {
      auto m = read_one(0.0);
      if (!m) break;
      if (m->contains("event")) events_.push_back(*m);
    }
    std::vector<Json> out;
    out.swap(events_);
    return out;
  }

 private:
  std::optional<Json> read_one(double wall_timeout_s) {
    for (;;) {
      const size_t nl = buf_.find('\n');
      if (nl != std::string::npos) {
        Json j = Json::parse(buf_.substr(0, nl), nullptr, false);
        buf_.erase(0, nl + 1);
        if (j.is_object()) return j;
        continue;
      }
      pollfd p{fd_, POLLIN, 0};
      if (poll(&p, 1, static_cast<int>(wall_timeout_s * 1000)) <= 0) return std::nullopt;
      char tmp[65536];
      const ssize_t n = recv(fd_, tmp, sizeof(tmp), 0);
      if (n <= 0) return std::nullopt;
      buf_.append(tmp, static_cast<size_t>(n));
    }
  }
  int fd_ = -1;
  int next_id_ = 0;
  std::string buf_;
  std::vector<Json> events_;
};

struct Options {
  uint64_t seed = 1;
  std::string world;
  std::string record;  // empty: no video
  double budget_s = 400.0;
  double wall_limit_s = 1800.0;
  std::string kill;  // vehicle to kill right after its take-off
  double gcs_loss = 0.0;       // the GCS link relay's loss probability, both vehicles
  double gcs_latency_s = 0.0;  // and its one-way latency
  std::string json_path;
  std::string camera_size = "384x216";
  double camera_fps = 15;
  bool quiet = false;
  std::string server, uav, gcs;
};

int usage() {
  std::fprintf(stderr, R"(usage: mbzirc2020-run [options]
Runs the MBZIRC 2020 balloon mission (seed 7.2): server, ground station, two UAV programs, lockstep at full speed.
  --seed N            balloon positions and sensor noise (default 1)
  --world FILE        default models/worlds/mbzirc2020.xml
  --record FILE.mp4   video of the run (default mbzirc2020_seedN.mp4); --no-record: none
  --budget S          sim-time limit of the mission (default 400)
  --kill VEHICLE      kill this vehicle right after its take-off (Competition Day 2)
  --gcs-loss P        impair both UAVs' GCS links in the server's relay: drop each datagram with
                      probability P (0-1, seeded; default 0)
  --gcs-latency S     and deliver the rest S seconds of sim time later (default 0)
  --camera-size WxH   the UAV cameras' size (default 384x216: 39 x 21 deg as the seed's oCam-1CGN-U)
  --camera-fps F      the UAV cameras' frame rate (default 15)
  --json FILE         write the summary as JSON
  --wall-limit S      wall-clock safety bound (default 1800)
  --quiet             only the summary
  --server/--uav/--gcs PATH  programs (default: beside this one / the build tree)
)");
  return 2;
}

}  // namespace

int main(int argc, char** argv) {
  Options o;
  o.world = std::string(UAVSIM_MODELS_DIR) + "/worlds/mbzirc2020.xml";
  o.server = UAVSIM_SERVER_PATH;
  o.uav = sibling(argv[0], "mbzirc2020-uav");
  o.gcs = sibling(argv[0], "mbzirc2020-gcs");
  bool record = true;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto next = [&]() -> const char* { return i + 1 < argc ? argv[++i] : nullptr; };
    const char* v = nullptr;
    if (a == "--no-record")
      record = false;
    else if (a == "--quiet")
      o.quiet = true;
    else if (a == "--help" || a == "-h")
      return usage();
    else if ((v = next()) == nullptr)
      return usage();
    else if (a == "--seed")
      o.seed = std::strtoull(v, nullptr, 10);
    else if (a == "--world")
      o.world = v;
    else if (a == "--record")
      o.record = v;
    else if (a == "--budget")
      o.budget_s = std::atof(v);
    else if (a == "--wall-limit")
      o.wall_limit_s = std::atof(v);
    else if (a == "--kill")
      o.kill = v;
    else if (a == "--gcs-loss")
      o.gcs_loss = std::atof(v);
    else if (a == "--gcs-latency")
      o.gcs_latency_s = std::atof(v);
    else if (a == "--json")
      o.json_path = v;
    else if (a == "--camera-size")
      o.camera_size = v;
    else if (a == "--camera-fps")
      o.camera_fps = std::atof(v);
    else if (a == "--server")
      o.server = v;
    else if (a == "--uav")
      o.uav = v;
    else if (a == "--gcs")
      o.gcs = v;
    else
      return usage();
  }
  if (!(o.gcs_loss >= 0.0 && o.gcs_loss <= 1.0) || !(o.gcs_latency_s >= 0.0)) return usage();
  if (record && o.record.empty()) o.record = "mbzirc2020_seed" + std::to_string(o.seed) + ".mp4";
  if (!record) o.record.clear();
  const size_t x = o.camera_size.find('x');
  if (x == std::string::npos) return usage();
  const std::string cam_opts = "width=" + o.camera_size.substr(0, x) +
                               ",height=" + o.camera_size.substr(x + 1) +
                               ",fps=" + std::to_string(static_cast<int>(o.camera_fps));
  const auto wall_start = Clock::now();
  auto wall_s = [&] { return std::chrono::duration<double>(Clock::now() - wall_start).count(); };
  auto say = [&](const std::string& s) {
    if (!o.quiet) {
      std::printf("%s\n", s.c_str());
      std::fflush(stdout);
    }
  };

  std::vector<Child> children;  // server, gcs, uav0, uav1
  children.reserve(4);
  int harness_error = 0;
  auto fail = [&](const std::string& why) {
    std::fprintf(stderr, "mbzirc2020-run: %s\n", why.c_str());
    harness_error = 4;
  };

  // 1. the server, on ephemeral ports, as fast as possible
  Child& server = children.emplace_back();
  server.name = "server";
  std::vector<std::string> sargs{o.server,
                                 o.world,
                                 "--rate",
                                 "0",
                                 "--seed",
                                 std::to_string(o.seed),
                                 "--mavlink-port",
                                 "0",
                                 "--api-port",
                                 "0",
                                 "--lockstep-timeout",
                                 "120",
                                 "--camera",
                                 "uav0_front:" + cam_opts,
                                 "--camera",
                                 "uav1_front:" + cam_opts};
  if (!o.record.empty()) sargs.insert(sargs.end(), {"--record", o.record});
  std::map<std::string, int> mavlink_port;
  int api_port = 0;
  if (!server.spawn(sargs, {})) {
    fail("cannot start " + o.server);
    return 4;
  }
  const std::regex mav_re(R"(uavsim-server: (\S+): MAVLink on tcp:[0-9.]+:(\d+))");
  const std::regex api_re(R"(sim API on tcp:[0-9.]+:(\d+))");
  while (api_port == 0 && wall_s() < 60) {
    pollfd p{server.fd, POLLIN, 0};
    poll(&p, 1, 200);
    for (const std::string& l : server.read_lines()) {
      say("[server] " + l);
      std::smatch m;
      if (std::regex_search(l, m, mav_re)) mavlink_port[m[1]] = std::stoi(m[2]);
      if (std::regex_search(l, m, api_re)) api_port = std::stoi(m[1]);
    }
    if (server.fd < 0) break;
  }
  Api api;
  std::set<std::string> killed;
  Json summary;
  int popped = 0, balloons_total = 0;
  std::vector<std::string> crashes;
  bool collision = false;
  double first_armed_s = -1, last_pop_s = -1, end_sim_s = 0;

  if (api_port == 0 || mavlink_port.size() < 2) {
    fail("the server did not start (no API / MAVLink ports)");
  } else if (!api.connect(api_port)) {
    fail("cannot connect to the sim API");
  } else {
    // 2. hold the clock and start from t = 0 with this seed, so every run of a seed starts alike
    api.request({{"op", "pause"}});
    api.request({{"op", "reset"}, {"seed", o.seed}});
    api.request({{"op", "subscribe_events"}});
    const std::string lockstep = "UAVSIM_LOCKSTEP=127.0.0.1:" + std::to_string(api_port) + "/0.05";

    // 3. the ground station; its link ports, then the server's GCS link relay in front of each
    // (seed 6.3)
    Child& gcs = children.emplace_back();
    gcs.name = "gcs";
    std::map<int, int> gcs_port;
    if (!gcs.spawn({o.gcs, "--uavs", "2"}, {lockstep})) fail("cannot start " + o.gcs);
    const std::regex gcs_re(R"(gcs: uav(\d+) link on udp:[0-9.]+:(\d+))");
    while (!harness_error && gcs_port.size() < 2 && wall_s() < 60 && gcs.fd >= 0) {
      pollfd p{gcs.fd, POLLIN, 0};
      poll(&p, 1, 200);
      for (const std::string& l : gcs.read_lines()) {
        say("[gcs] " + l);
        std::smatch m;
        if (std::regex_search(l, m, gcs_re)) gcs_port[std::stoi(m[1])] = std::stoi(m[2]);
      }
    }
    if (!harness_error && gcs_port.size() < 2) fail("the ground station did not start");
    for (int i = 0; i < 2 && !harness_error; ++i) {
      const Json r = api.request({{"op", "gcs_link_open"},
                                  {"vehicle", i},
                                  {"gcs_target_host", "127.0.0.1"},
                                  {"gcs_target_port", gcs_port[i]}});
      if (!r.value("ok", false)) {
        fail("gcs_link_open: " + r.dump());
        break;
      }
      const int uav_port = r["result"]["uav_port"].get<int>();
      if (o.gcs_loss > 0.0 || o.gcs_latency_s > 0.0) {
        // impaired from t = 0, before the UAV program sends anything
        const Json ir = api.request({{"op", "gcs_link_impair"},
                                     {"vehicle", i},
                                     {"loss", o.gcs_loss},
                                     {"latency_s", o.gcs_latency_s}});
        if (!ir.value("ok", false)) {
          fail("gcs_link_impair: " + ir.dump());
          break;
        }
      }
      // 4. the UAV programs
      Child& u = children.emplace_back();
      u.name = "uav" + std::to_string(i);
      if (!u.spawn({o.uav, "--index", std::to_string(i), "--mavlink",
                    "tcp:127.0.0.1:" + std::to_string(mavlink_port[u.name]), "--gcs",
                    "127.0.0.1:" + std::to_string(uav_port)},
                   {lockstep})) {
        fail("cannot start " + o.uav);
      }
    }
    // 5. once all three have joined the lockstep, let the clock go
    while (!harness_error) {
      const Json s = api.request({{"op", "status"}});
      if (s.value("ok", false) && s["result"].value("lockstep_clients", 0) >= 3) break;
      if (wall_s() > 120) fail("the mission programs did not join the lockstep");
      for (Child& c : children) {
        for (const std::string& l : c.read_lines()) say("[" + c.name + "] " + l);
      }
      usleep(20000);
    }
    if (!harness_error) {
      api.request({{"op", "resume"}});
      say("mbzirc2020-run: seed " + std::to_string(o.seed) + ", budget " +
          std::to_string(static_cast<int>(o.budget_s)) + " s sim" +
          (o.kill.empty() ? "" : ", killing " + o.kill + " after its take-off"));
    }

    // 6. follow the programs and the event stream until they finish or the budget is spent
    auto last_status = Clock::now();
    double sim_s = 0;
    while (!harness_error) {
      std::vector<pollfd> fds{{api.fd(), POLLIN, 0}};
      for (Child& c : children) {
        if (c.fd >= 0) fds.push_back({c.fd, POLLIN, 0});
      }
      poll(fds.data(), fds.size(), 200);
      for (Child& c : children) {
        for (const std::string& l : c.read_lines()) say("[" + c.name + "] " + l);
      }
      for (const Json& e : api.take_events()) {
        if (e.value("event", "") != "sim_event") continue;
        const std::string type = e.value("type", ""), veh = e.value("vehicle_name", "");
        const double t = e.value("time", 0.0);
        const std::string detail = e.value("detail", "");
        if (type == "takeoff" && first_armed_s < 0)
          first_armed_s = t;  // the GCS start: first take-off
        if (type == "balloon_popped") last_pop_s = t;
        if (type == "vehicle_killed") killed.insert(veh);
        if (type == "crash" && !killed.count(veh)) {
          crashes.push_back(veh + " at " + std::to_string(t) + " s: " + detail);
          collision = collision || detail.find("collision") != std::string::npos;
        }
        if (type == "balloon_popped" || type == "crash" || type == "vehicle_killed" ||
            type == "takeoff" || type == "touchdown") {
          char buf[256];
          std::snprintf(buf, sizeof(buf), "[event] t=%.2f %s %s %s", t, type.c_str(), veh.c_str(),
                        detail.c_str());
          say(buf);
        }
        if (type == "takeoff" && veh == o.kill && !killed.count(veh)) {
          api.request({{"op", "kill_vehicle"},
                       {"vehicle", veh},
                       {"reason", "Competition Day 2 malfunction"}});
          killed.insert(veh);
        }
      }
      bool all_done = true;
      for (size_t i = 1; i < children.size(); ++i)
        all_done = all_done && children[i].reap() && children[i].fd < 0;
      if (Clock::now() - last_status > std::chrono::milliseconds(500) || all_done) {
        last_status = Clock::now();
        const Json s = api.request({{"op", "status"}});
        if (s.value("ok", false)) sim_s = s["result"].value("time_s", 0.0);
      }
      if (all_done) break;
      if (sim_s > o.budget_s) {
        say("mbzirc2020-run: sim-time budget spent");
        break;
      }
      if (wall_s() > o.wall_limit_s) {
        say("mbzirc2020-run: wall-clock limit reached");
        break;
      }
      if (server.reap()) {
        fail("the server exited");
        break;
      }
    }

    // 7. score from ground truth
    const Json b = api.request({{"op", "balloons"}});
    if (b.value("ok", false)) {
      end_sim_s = b["result"].value("time_s", 0.0);
      for (const Json& x : b["result"]["balloons"]) {
        ++balloons_total;
        if (x.value("popped", false)) {
          ++popped;
          last_pop_s = std::max(last_pop_s, x.value("popped_time_s", 0.0));
        }
      }
      summary["balloons"] = b["result"]["balloons"];
    }
    // the relay's counters: what the impairment did to each GCS link
    summary["gcs_links"] = Json::array();
    for (int i = 0; i < 2; ++i) {
      const Json g = api.request({{"op", "gcs_link_stats"}, {"vehicle", i}});
      if (g.value("ok", false)) summary["gcs_links"].push_back(g["result"]);
    }
  }

  // 8. stop everything we started: the programs, then the server (SIGINT: it finishes the video)
  for (size_t i = children.size(); i-- > 1;) children[i].stop(SIGTERM, 5.0);
  server.stop(SIGINT, 60.0);
  for (Child& c : children) {
    for (const std::string& l : c.read_lines()) say("[" + c.name + "] " + l);
  }

  const bool success =
      harness_error == 0 && balloons_total > 0 && popped == balloons_total && crashes.empty();
  const double mission_s =
      (first_armed_s >= 0 && last_pop_s >= 0) ? last_pop_s - first_armed_s : -1;
  std::printf("==== MBZIRC 2020 balloons, seed %llu%s ====\n",
              static_cast<unsigned long long>(o.seed),
              o.kill.empty() ? "" : (" (" + o.kill + " killed after take-off)").c_str());
  std::printf("balloons popped: %d/%d\n", popped, balloons_total);
  if (mission_s >= 0) {
    std::printf("mission time: %.1f s sim (first take-off at t=%.1f s, last balloon at t=%.1f s)\n",
                mission_s, first_armed_s, last_pop_s);
  } else {
    std::printf("mission time: n/a\n");
  }
  std::printf("collisions between UAVs: %s\n", collision ? "yes" : "none");
  std::printf("crashes: %s\n", crashes.empty() ? "none" : "");
  for (const std::string& c : crashes) std::printf("  %s\n", c.c_str());
  if (!killed.empty())
    std::printf("killed on purpose: %s\n", *killed.begin() == "" ? "?" : killed.begin()->c_str());
  std::printf("sim time: %.1f s, wall time: %.1f s\n", end_sim_s, wall_s());
  std::printf("video: %s\n", o.record.empty() ? "none" : o.record.c_str());
  std::printf("RESULT: %s\n", success ? "SUCCESS" : "FAILURE");
  std::fflush(stdout);

  if (!o.json_path.empty()) {
    summary["seed"] = o.seed;
    summary["popped"] = popped;
    summary["total"] = balloons_total;
    summary["mission_time_s"] = mission_s;
    summary["start_time_s"] = first_armed_s;
    summary["last_pop_time_s"] = last_pop_s;
    summary["collision"] = collision;
    summary["crashes"] = crashes;
    summary["killed"] = std::vector<std::string>(killed.begin(), killed.end());
    summary["sim_time_s"] = end_sim_s;
    summary["wall_time_s"] = wall_s();
    summary["video"] = o.record;
    summary["success"] = success;
    std::ofstream(o.json_path) << summary.dump(2) << "\n";
  }
  if (harness_error) return harness_error;
  return success ? 0 : 1;
}
