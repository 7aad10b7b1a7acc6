// Soak: a uavsim-server with 100 vehicles at full speed while MAVLink and sim API clients connect,
// command, pipeline and drop, for a stretch of sim time. Reports the server's RSS, open descriptors and
// threads over time, then checks that every vehicle is still controllable (GUIDED, arm and take-off
// accepted, and it climbs). A figure-producing program, not a test and not a CI gate: loopback only,
// every client loop bounded.
//
//   soak_bench [--sim-s S] [--max-wall-s W] [--port-base P] [--server PATH] [--world W]
//
// The server runs as a child process (its /proc/PID is what is measured): MAVLink TCP on P + 10 i for
// vehicle i, the sim API on P - 10.
#include <arpa/inet.h>
#include <dirent.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <signal.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <functional>
#include <map>
#include <mutex>
#include <nlohmann/json.hpp>
#include <optional>
#include <random>
#include <sstream>
#include <string>
#include <thread>
#include <tuple>
#include <utility>
#include <vector>

#include "uavsim/common/mavlink/codec.hpp"
#include "uavsim/common/mavlink/parser.hpp"
#include "uavsim/common/mavlink/generated/messages.hpp"
#include "uavsim/common/parse_number.hpp"

#ifndef UAVSIM_SERVER_BIN
#define UAVSIM_SERVER_BIN "uavsim-server"
#endif

namespace mav = uavsim::common::mavlink;
using Json = nlohmann::json;
using Clock = std::chrono::steady_clock;

namespace {

constexpr int kVehicles = 100;
constexpr double kIoTimeout_s = 2.0;  // every client wait is bounded by this much wall time

double since_s(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

// --- sockets ---

int connect_loopback(int port) {
  const int fd = socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
  if (fd < 0) return -1;
  sockaddr_in sa{};
  sa.sin_family = AF_INET;
  sa.sin_port = htons(static_cast<std::uint16_t>(port));
  sa.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  if (connect(fd, reinterpret_cast<sockaddr*>(&sa), sizeof(sa)) != 0) {
    close(fd);
    return -1;
  }
  const int one = 1;
  setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof(one));
  timeval tv{2, 0};
  setsockopt(fd, SOL_SOCKET, SO_SNDTIMEO, &tv, sizeof(tv));
  return fd;
}

void send_all(int fd, const void* data, std::size_t n) {
  const auto* p = static_cast<const std::uint8_t*>(data);
  while (n > 0) {
    const ssize_t k = ::send(fd, p, n, MSG_NOSIGNAL);
    if (k <= 0) return;  // peer gone or send timeout: the episode just ends
    p += k;
    n -= static_cast<std::size_t>(k);
  }
}

// closes with a reset instead of an orderly end of stream
void close_abruptly(int fd) {
  linger l{1, 0};
  setsockopt(fd, SOL_SOCKET, SO_LINGER, &l, sizeof(l));
  close(fd);
}

// reads what is there within timeout_s; false on end of stream or error
bool read_some(int fd, std::vector<std::uint8_t>* buf, double timeout_s) {
  pollfd p{fd, POLLIN, 0};
  if (poll(&p, 1, static_cast<int>(timeout_s * 1000)) <= 0) return true;
  std::uint8_t tmp[65536];
  const ssize_t n = recv(fd, tmp, sizeof(tmp), MSG_DONTWAIT);
  if (n <= 0) return false;
  buf->assign(tmp, tmp + n);
  return true;
}

// --- MAVLink client ---

class MavClient {
 public:
  explicit MavClient(int port) : fd_(connect_loopback(port)) {}
  ~MavClient() {
    if (fd_ >= 0) close(fd_);
  }
  bool ok() const { return fd_ >= 0; }
  int release() { return std::exchange(fd_, -1); }

  template <class Msg>
  std::vector<std::uint8_t> frame(const Msg& m) {
    const mav::EncodedFrame f = mav::encode(mav::FrameHeader{255, 190, seq_++, mav::Version::kV2, std::nullopt}, m);
    return {f.bytes.data(), f.bytes.data() + f.size};
  }
  void send_bytes(const std::vector<std::uint8_t>& b) { send_all(fd_, b.data(), b.size()); }
  template <class Msg>
  void send(const Msg& m) { send_bytes(frame(m)); }

  static mav::msg::CommandLong command(int vehicle, std::uint16_t cmd, std::array<float, 7> p = {}) {
    mav::msg::CommandLong c;
    c.target_system = static_cast<std::uint8_t>(vehicle + 1);
    c.target_component = 1;
    c.command = cmd;
    c.param1 = p[0], c.param2 = p[1], c.param3 = p[2], c.param4 = p[3];
    c.param5 = p[4], c.param6 = p[5], c.param7 = p[6];
    return c;
  }

  // collects COMMAND_ACKs (command -> result) until `count` arrived or timeout_s of wall time
  std::map<std::uint16_t, int> acks(std::size_t count, double timeout_s = kIoTimeout_s) {
    std::map<std::uint16_t, int> got;
    std::size_t n = 0;
    const auto t0 = Clock::now();
    std::vector<std::uint8_t> buf;
    while (n < count && since_s(t0) < timeout_s) {
      if (!read_some(fd_, &buf, 0.05)) break;
      parser_.feed(buf, [&](const mav::Frame& f) {
        if (f.msgid != mav::msg::CommandAck::kId) return;
        const auto a = mav::msg::CommandAck::decode(f.payload.data());
        got[a.command] = a.result;
        ++n;
      });
      buf.clear();
    }
    return got;
  }

 private:
  int fd_ = -1;
  std::uint8_t seq_ = 0;
  mav::Parser parser_;
};

// --- sim API client ---

class ApiClient {
 public:
  explicit ApiClient(int port) : fd_(connect_loopback(port)) {
    if (fd_ >= 0 && !line(&hello_)) {
      close(fd_);
      fd_ = -1;
    }
  }
  ~ApiClient() {
    if (fd_ >= 0) close(fd_);
  }
  bool ok() const { return fd_ >= 0; }
  int release() { return std::exchange(fd_, -1); }
  void send_raw(const std::string& s) { send_all(fd_, s.data(), s.size()); }

  // the next line (a reply or an event) within kIoTimeout_s
  bool line(std::string* out) {
    const auto t0 = Clock::now();
    for (;;) {
      const auto nl = in_.find('\n');
      if (nl != std::string::npos) {
        *out = in_.substr(0, nl);
        in_.erase(0, nl + 1);
        return true;
      }
      if (since_s(t0) > kIoTimeout_s) return false;
      std::vector<std::uint8_t> buf;
      if (!read_some(fd_, &buf, 0.05)) return false;
      in_.append(buf.begin(), buf.end());
    }
  }
  // a request and its reply, matched by id (events and late replies to earlier requests skipped); null
  // after 10 s
  Json request(Json req) {
    const std::uint64_t id = next_id_++;
    req["id"] = id;
    send_raw(req.dump() + "\n");
    const auto t0 = Clock::now();
    std::string l;
    while (since_s(t0) < 10.0) {
      if (!line(&l)) continue;
      Json j = Json::parse(l, nullptr, false);
      if (j.is_object() && j.contains("id") && j["id"] == id) return j;
    }
    return nullptr;
  }

 private:
  int fd_ = -1;
  std::string in_;
  std::string hello_;
  std::uint64_t next_id_ = 1;
};

// --- the server under test ---

struct Sample {
  double wall_s = 0, sim_s = 0;
  long rss_kb = 0, threads = 0, fds = 0;
  long events = 0;  // events recorded by the server since start (status "events")
};

long status_field_kb(pid_t pid, const std::string& key) {
  std::ifstream f("/proc/" + std::to_string(pid) + "/status");
  std::string l;
  while (std::getline(f, l)) {
    if (l.rfind(key + ":", 0) == 0) return std::strtol(l.c_str() + key.size() + 1, nullptr, 10);
  }
  return -1;
}

long count_fds(pid_t pid) {
  long n = 0;
  if (DIR* d = opendir(("/proc/" + std::to_string(pid) + "/fd").c_str())) {
    while (const dirent* e = readdir(d)) n += e->d_name[0] != '.';
    closedir(d);
  }
  return n;
}

// --- churn: clients that connect, command, pipeline and drop ---

struct Counts {
  std::atomic<long> mav_episodes{0}, api_episodes{0}, connect_failures{0}, acks{0}, api_replies{0};
};

void mavlink_episode(std::mt19937& rng, int port_base, Counts& counts) {
  const int v = static_cast<int>(rng() % kVehicles);
  MavClient c(port_base + 10 * v);
  if (!c.ok()) {
    counts.connect_failures++;
    return;
  }
  counts.mav_episodes++;
  mav::msg::Heartbeat hb;
  hb.type = 6;  // MAV_TYPE_GCS
  std::vector<std::uint8_t> burst = c.frame(hb);
  auto add = [&](const std::vector<std::uint8_t>& f) { burst.insert(burst.end(), f.begin(), f.end()); };
  switch (rng() % 6) {
    case 0: {  // pipelined harmless commands, every ack read
      for (int k = 0; k < 10; ++k) add(c.frame(MavClient::command(v, 31000)));            // unsupported
      add(c.frame(MavClient::command(v, 512, {static_cast<float>(mav::msg::Heartbeat::kId)})));  // REQUEST_MESSAGE
      c.send_bytes(burst);
      counts.acks += static_cast<long>(c.acks(11).size());
      break;
    }
    case 1: {  // fly: GUIDED, arm, take off, then LAND (the vehicle lands and disarms on its own)
      add(c.frame(MavClient::command(v, 176, {1, 4})));
      add(c.frame(MavClient::command(v, 400, {1})));
      add(c.frame(MavClient::command(v, 22, {0, 0, 0, 0, 0, 0, 3})));
      c.send_bytes(burst);
      counts.acks += static_cast<long>(c.acks(3).size());
      c.send(MavClient::command(v, 176, {1, 9}));
      counts.acks += static_cast<long>(c.acks(1).size());
      break;
    }
    case 2: {  // pipeline and reset the connection without reading
      for (int k = 0; k < 20; ++k) add(c.frame(MavClient::command(v, 511, {33, 20000})));  // SET_MESSAGE_INTERVAL
      c.send_bytes(burst);
      close_abruptly(c.release());
      break;
    }
    case 3: {  // half a frame, then gone
      const auto f = c.frame(MavClient::command(v, 31000));
      add(std::vector<std::uint8_t>(f.begin(), f.begin() + static_cast<long>(f.size() / 2)));
      c.send_bytes(burst);
      break;
    }
    case 4: {  // garbage, then a good command that must still be answered
      for (int k = 0; k < 2000; ++k) burst.push_back(static_cast<std::uint8_t>(rng()));
      add(c.frame(MavClient::command(v, 31000)));
      c.send_bytes(burst);
      counts.acks += static_cast<long>(c.acks(1).size());
      break;
    }
    default: {  // a reader that asks for every stream at 50 Hz and reads nothing for a while
      mav::msg::RequestDataStream r;
      r.target_system = static_cast<std::uint8_t>(v + 1);
      r.req_message_rate = 50;
      r.start_stop = 1;
      add(c.frame(r));
      const int fd = c.release();
      const int small = 4096;
      setsockopt(fd, SOL_SOCKET, SO_RCVBUF, &small, sizeof(small));
      send_all(fd, burst.data(), burst.size());
      std::this_thread::sleep_for(std::chrono::milliseconds(300));
      close(fd);
      break;
    }
  }
}

void api_episode(std::mt19937& rng, int api_port, Counts& counts) {
  ApiClient c(api_port);
  if (!c.ok()) {
    counts.connect_failures++;
    return;
  }
  counts.api_episodes++;
  const std::vector<std::string> requests = {
      R"({"op":"status","id":1})",   R"({"op":"vehicles","id":2})",  R"({"op":"events","from_seq":0})",
      R"({"op":"no_such_op","id":4})", R"({"op":"status",)",         R"({"op":"vehicles","id":[1]})",
      R"({"op":"step","steps":"x"})"};  // bad_field: refused before it pauses anything
  std::string burst;
  for (int k = 0; k < 20; ++k) burst += requests[rng() % requests.size()] + "\n";
  switch (rng() % 5) {
    case 0: {  // pipelined, every reply read
      c.send_raw(burst);
      std::string l;
      for (int k = 0; k < 20 && c.line(&l); ++k) counts.api_replies++;
      break;
    }
    case 1: {  // event subscriber for a moment
      c.send_raw(R"({"op":"subscribe_events","from_seq":0})" "\n");
      std::string l;
      const auto t0 = Clock::now();
      while (since_s(t0) < 0.3 && c.line(&l)) counts.api_replies++;
      break;
    }
    case 2:  // pipelined, reset without reading
      c.send_raw(burst);
      close_abruptly(c.release());
      break;
    case 3:  // half a request, then gone
      c.send_raw(R"({"op":"vehi)");
      break;
    default: {  // a line past the 1 MiB limit, then a good request on the same connection
      c.send_raw(std::string((1u << 20) + 10, 'x') + "\n");
      const Json r = c.request({{"op", "status"}});
      if (!r.is_null()) counts.api_replies++;
      break;
    }
  }
}

// --- the final check ---

Json vehicles(ApiClient& api) {
  const Json r = api.request({{"op", "vehicles"}});
  if (r.is_object() && r.contains("result") && r["result"].is_object()) return r["result"].value("vehicles", Json::array());
  std::fprintf(stderr, "soak_bench: unexpected vehicles reply: %s\n", r.dump().c_str());
  return Json::array();
}

}  // namespace

constexpr const char* kUsage =
    "usage: soak_bench [--sim-s S] [--max-wall-s W] [--port-base P] [--server PATH] [--world W]\n"
    "  --sim-s S        sim seconds of churn (default 1800)\n"
    "  --max-wall-s W   wall-time limit of the churn (default 3600)\n"
    "  --port-base P    MAVLink port of vehicle 0 (default 46000; the API listens on P - 10)\n"
    "  --server PATH    the uavsim-server binary (default: the one built beside this bench)\n"
    "  --world W        the world (default grid100; it must have 100 vehicles)\n";

// the wall time since the start, for the phase lines (a hang shows as the phase it is stuck in)
void phase(Clock::time_point wall0, const char* what) {
  std::printf("[wall %6.0f s] %s\n", since_s(wall0), what);
  std::fflush(stdout);
}

// "" while the server runs, else how it ended (the soak is over then: nothing left to check)
std::string server_ended(pid_t pid) {
  int status = 0;
  if (waitpid(pid, &status, WNOHANG) != pid) return "";
  if (WIFSIGNALED(status)) return "killed by signal " + std::to_string(WTERMSIG(status));
  return "exited with status " + std::to_string(WEXITSTATUS(status));
}

int run(int argc, char** argv, pid_t* child) {
  double sim_s = 1800, max_wall_s = 3600;
  int port_base = 46000;
  std::string server = UAVSIM_SERVER_BIN, world = "grid100";
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--help" || a == "-h") {
      std::fputs(kUsage, stdout);
      return 0;
    }
    const char* v = i + 1 < argc ? argv[i + 1] : nullptr;
    bool ok = v != nullptr;
    if (ok && a == "--sim-s") ok = uavsim::common::parse_double(v, 1.0, 1e6, &sim_s);
    else if (ok && a == "--max-wall-s") ok = uavsim::common::parse_double(v, 1.0, 1e6, &max_wall_s);
    else if (ok && a == "--port-base") ok = uavsim::common::parse_integer(v, 1034, 64535 - 10 * kVehicles, &port_base);
    else if (ok && a == "--server") server = v;
    else if (ok && a == "--world") world = v;
    else ok = false;
    if (!ok) {
      std::fprintf(stderr, "soak_bench: bad option or value at '%s'\n%s", a.c_str(), kUsage);
      return 2;
    }
    ++i;
  }
  const int api_port = port_base - 10;
  signal(SIGPIPE, SIG_IGN);

  // the server, as fast as it can go, its output to a log
  const pid_t pid = fork();
  *child = pid;
  if (pid == 0) {
    const std::string mp = std::to_string(port_base), ap = std::to_string(api_port);
    if (FILE* log = std::fopen("/tmp/uavsim_soak_server.log", "w")) {
      dup2(fileno(log), 1);
      dup2(fileno(log), 2);
    }
    execl(server.c_str(), server.c_str(), world.c_str(), "--fast", "--mavlink-port", mp.c_str(), "--out", "none",
          "--api-port", ap.c_str(), "--no-cameras", "--quiet", static_cast<char*>(nullptr));
    _exit(127);
  }
  const auto wall0 = Clock::now();
  std::unique_ptr<ApiClient> monitor;
  while (since_s(wall0) < 600) {  // a loaded machine can take minutes to compose 100 vehicles
    monitor = std::make_unique<ApiClient>(api_port);
    if (monitor->ok()) break;
    if (waitpid(pid, nullptr, WNOHANG) == pid) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(200));
  }
  if (!monitor || !monitor->ok() || waitpid(pid, nullptr, WNOHANG) != 0) {  // not up, or another one answered
    std::fprintf(stderr, "soak_bench: the server did not come up (see /tmp/uavsim_soak_server.log)\n");
    kill(pid, SIGKILL);
    return 1;
  }
  // the server's sim time and event count (-1 without a status reply)
  auto server_status = [&]() -> std::pair<double, long> {
    const Json r = monitor->request({{"op", "status"}});
    if (r.is_object() && r.contains("result") && r["result"].is_object()) {
      return {r["result"].value("time_s", -1.0), r["result"].value("events", -1L)};
    }
    std::fprintf(stderr, "soak_bench: unexpected status reply: %s\n", r.dump().c_str());
    return {-1.0, -1};
  };
  auto sim_time = [&] { return server_status().first; };
  auto sample = [&] {
    Sample s;
    s.wall_s = since_s(wall0);
    std::tie(s.sim_s, s.events) = server_status();
    s.rss_kb = status_field_kb(pid, "VmRSS");
    s.threads = status_field_kb(pid, "Threads");
    s.fds = count_fds(pid);
    return s;
  };
  std::vector<Sample> samples{sample()};
  std::printf("soak: %s %s, %d vehicles, %.0f s of sim time (wall limit %.0f s)\n", server.c_str(), world.c_str(),
              kVehicles, sim_s, max_wall_s);

  // churn until the sim time is reached: 3 MAVLink and 2 API client threads, fixed seeds
  Counts counts;
  std::atomic<bool> stop{false};
  std::vector<std::thread> churn;
  for (int k = 0; k < 5; ++k) {
    churn.emplace_back([&, k] {
      std::mt19937 rng(1000 + k);
      while (!stop.load()) {
        if (k < 3) mavlink_episode(rng, port_base, counts);
        else api_episode(rng, api_port, counts);
      }
    });
  }
  // progress: every 1/60 of the sim time asked for, and at least once a wall minute
  double next_print_s = 0, next_print_wall_s = 0;
  int monitor_failures = 0;
  std::string churn_end = "the wall-time limit";
  while (since_s(wall0) < max_wall_s) {
    std::this_thread::sleep_for(std::chrono::seconds(2));
    if (const std::string ended = server_ended(pid); !ended.empty()) {
      churn_end = "the server " + ended;
      break;
    }
    const Sample s = sample();
    if (s.sim_s < 0) {  // no status reply: give up after a few in a row (reported below)
      if (++monitor_failures >= 5) {
        churn_end = "the server's API not answering status (5 times in a row)";
        break;
      }
      continue;
    }
    monitor_failures = 0;
    samples.push_back(s);
    if (s.sim_s >= next_print_s || s.wall_s >= next_print_wall_s) {
      std::printf(
          "  wall %6.0f s  sim %7.1f s  rss %7.1f MiB  fds %4ld  threads %3ld  events %6ld  "
          "episodes mav %ld api %ld\n",
          s.wall_s, s.sim_s, s.rss_kb / 1024.0, s.fds, s.threads, s.events,
          counts.mav_episodes.load(), counts.api_episodes.load());
      std::fflush(stdout);
      while (next_print_s <= s.sim_s) next_print_s += sim_s / 60;
      next_print_wall_s = s.wall_s + 60;
    }
    if (s.sim_s >= sim_s) {
      churn_end = "the sim time asked for";
      break;
    }
  }
  phase(wall0, ("churn ended at " + churn_end + "; stopping the client threads").c_str());
  stop = true;
  for (auto& t : churn) t.join();
  std::this_thread::sleep_for(std::chrono::seconds(1));
  const Sample after_churn = sample();
  const bool reached = after_churn.sim_s >= sim_s;
  // a dead or mute server leaves nothing to check: say so now instead of waiting out every bounded wait
  if (const std::string ended = server_ended(pid); !ended.empty() || after_churn.sim_s < 0) {
    std::printf("FAIL: the server %s after %.0f s of wall time (its log: /tmp/uavsim_soak_server.log)\n",
                ended.empty() ? "stopped answering the API" : ended.c_str(), since_s(wall0));
    kill(pid, SIGKILL);
    waitpid(pid, nullptr, 0);
    return 1;
  }

  // every vehicle back on the ground: LAND for any still armed, then wait (bounded) until all are disarmed
  phase(wall0, "landing the vehicles still armed");
  Json vs = vehicles(*monitor);
  for (const Json& v : vs) {
    if (!v["armed"].get<bool>()) continue;
    MavClient c(port_base + 10 * v["index"].get<int>());
    c.send(MavClient::command(v["index"].get<int>(), 176, {1, 9}));
    c.acks(1);
  }
  const auto land0 = Clock::now();
  int armed = 0;
  do {
    std::this_thread::sleep_for(std::chrono::milliseconds(500));
    armed = 0;
    for (const Json& v : vehicles(*monitor)) armed += v["armed"].get<bool>() ? 1 : 0;
  } while (armed > 0 && since_s(land0) < 120);

  // every vehicle controllable: GUIDED, arm and take off to 5 m accepted, and it climbs past 2 m
  phase(wall0, "final check: GUIDED, arm and take off on every vehicle");
  const double check_sim0 = sim_time();
  std::vector<std::unique_ptr<MavClient>> gcs;
  int accepted = 0;
  std::map<std::string, int> refusals;
  int silent_in_a_row = 0;  // vehicles that acknowledged nothing, one after the other
  for (int v = 0; v < kVehicles; ++v) {
    if (silent_in_a_row >= 5) {  // the endpoint is mute: 10 s a vehicle would only delay the verdict
      refusals["not tried: 5 vehicles in a row acknowledged nothing"] = kVehicles - v;
      break;
    }
    auto c = std::make_unique<MavClient>(port_base + 10 * v);
    mav::msg::Heartbeat hb;
    hb.type = 6;
    c->send(hb);
    c->send(MavClient::command(v, 176, {1, 4}));
    c->send(MavClient::command(v, 400, {1}));
    c->send(MavClient::command(v, 22, {0, 0, 0, 0, 0, 0, 5}));
    const auto a = c->acks(3, 10.0);
    const bool ok = a.size() == 3 && std::all_of(a.begin(), a.end(), [](const auto& kv) { return kv.second == 0; });
    accepted += ok ? 1 : 0;
    silent_in_a_row = a.empty() ? silent_in_a_row + 1 : 0;
    if (!ok) {
      std::ostringstream why;
      for (const auto& [cmd, result] : a) why << cmd << "=" << result << " ";
      refusals[why.str().empty() ? "no ack" : why.str()]++;
    }
    gcs.push_back(std::move(c));
  }
  phase(wall0, "final check: waiting for every vehicle to climb past 2 m");
  const auto climb0 = Clock::now();
  int climbed = 0;
  do {
    std::this_thread::sleep_for(std::chrono::milliseconds(500));
    climbed = 0;
    for (const Json& v : vehicles(*monitor)) climbed += v["position_enu_m"][2].get<double>() > 2.0 ? 1 : 0;
  } while (climbed < kVehicles && since_s(climb0) < 120);
  gcs.clear();
  std::this_thread::sleep_for(std::chrono::seconds(1));
  const Sample end = sample();

  // report: RSS and descriptors after warm-up (10 % of the run) against the end of the churn
  const Sample* warm = &samples.front();
  for (const Sample& s : samples) {
    if (s.sim_s >= 0.1 * sim_s) {
      warm = &s;
      break;
    }
  }
  long rss_max = 0, fds_max = 0;
  for (const Sample& s : samples) {
    rss_max = std::max(rss_max, s.rss_kb);
    fds_max = std::max(fds_max, s.fds);
  }
  std::printf("\nsim time %.1f s in %.0f s of wall time (%.2fx real time)%s\n", after_churn.sim_s,
              after_churn.wall_s, after_churn.sim_s / after_churn.wall_s,
              reached ? "" : "  ** stopped at the wall-time limit **");
  std::printf("episodes: MAVLink %ld, API %ld; acks %ld, API replies %ld; failed connects %ld\n",
              counts.mav_episodes.load(), counts.api_episodes.load(), counts.acks.load(),
              counts.api_replies.load(), counts.connect_failures.load());
  std::printf(
      "RSS MiB: start %.1f, at %.0f s sim %.1f, end of churn %.1f, max %.1f, after the final check %.1f\n",
      samples.front().rss_kb / 1024.0, warm->sim_s, warm->rss_kb / 1024.0, after_churn.rss_kb / 1024.0,
      rss_max / 1024.0, end.rss_kb / 1024.0);
  std::printf("events recorded by the server: %ld\n", after_churn.events);
  std::printf("fds: start %ld, at %.0f s sim %ld, end of churn %ld, max %ld, after the final check %ld\n",
              samples.front().fds, warm->sim_s, warm->fds, after_churn.fds, fds_max, end.fds);
  std::printf("threads: start %ld, end %ld\n", samples.front().threads, end.threads);
  std::printf("final check (from sim %.1f s): %d still armed after landing; GUIDED+arm+takeoff accepted by %d/%d, "
              "climbed past 2 m: %d/%d\n",
              check_sim0, armed, accepted, kVehicles, climbed, kVehicles);
  for (const auto& [why, n] : refusals) std::printf("  refused (%s): %d\n", why.c_str(), n);

  monitor.reset();
  kill(pid, SIGTERM);
  int status = 0;
  waitpid(pid, &status, 0);
  const bool pass = reached && accepted == kVehicles && climbed == kVehicles && end.fds <= samples.front().fds + 2;
  std::printf("%s\n", pass ? "PASS" : "FAIL");
  return pass ? 0 : 1;
}

int main(int argc, char** argv) {
  // the server never outlives the soak, whatever ends it
  pid_t child = 0;
  try {
    return run(argc, argv, &child);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "soak_bench: %s\n", e.what());
    if (child > 0) kill(child, SIGKILL);
    return 1;
  }
}
