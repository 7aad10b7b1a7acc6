// uavsim-server as a user meets it: a bad option, a world it cannot find, a port in use say why
// (and what to do); a run prints one line per event and a summary, unless --quiet.
#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "../../support/piped_child.hpp"
#include "../../support/run_command.hpp"

namespace {

using ServerRun = uavsim::testing::CommandRun;
using uavsim::testing::has;

// env: "NAME=VALUE ..." set for the server alone, or ""
ServerRun run_server_env(const std::string& env, const std::string& args) {
  return uavsim::testing::run_command((env.empty() ? "" : "env " + env + " ") + std::string(UAVSIM_SERVER_BIN) +
                                      " " + args);
}

ServerRun run_server(const std::string& args) { return run_server_env("", args); }

const std::string kWorlds = std::string(" --models-dir ") + UAVSIM_MODELS_DIR;

TEST(ServerCli, BadOptionsSayWhy) {
  ServerRun r = run_server("empty --rate -1");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_TRUE(has(r, "uavsim-server: --rate needs")) << r.output;
  r = run_server("empty --mavlink-port 99999");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_TRUE(has(r, "--mavlink-port needs a port")) << r.output;
}

// --hover: with no client at all, every vehicle takes off and holds (the floor of a mission's wall
// time); the altitude is range-checked like every number from outside
TEST(ServerCli, HoverTakesEveryVehicleUpAndHoldsWithNoClient) {
  ServerRun r = run_server("mbzirc2020" + kWorlds +
                           " --hover 4 --rate 0 --duration 20 --api-port -1 --mavlink-port -1"
                           " --out none --no-cameras");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_TRUE(has(r, "uavsim-server: --hover: every vehicle takes off to 4 m and holds"))
      << r.output;
  EXPECT_TRUE(has(r, "uavsim-server: --hover: all 2 vehicle(s) at 4 m by t=")) << r.output;
  EXPECT_TRUE(has(r, "2 vehicle(s), 0 crash(es)")) << r.output;
  for (const char* bad : {"0.1", "1e308", "nan", "-4", "x"}) {
    r = run_server(std::string("empty --hover ") + bad);
    EXPECT_EQ(r.exit_code, 2) << bad;
    EXPECT_TRUE(has(r, "--hover needs metres of altitude from 0.5 to 1000"))
        << bad << ": " << r.output;
  }
}

// --render-cameras: with no client the server renders the named cameras' frames at their rates, in
// sim time and none dropped, so a run of fixed sim duration renders an exact number (frame k is
// taken at the first control step at or after k / fps, and the last step taken is before the end);
// what the world does not have is refused before the clock starts
TEST(ServerCli, RenderCamerasRendersEveryFrameDueWithNoClient) {
  const std::string base = "mbzirc2017" + kWorlds +
                           " --hover 4 --rate 0 --duration 3 --api-port -1 --mavlink-port -1"
                           " --out none";
  // uav0_down gives 7 frames a sim second (the world's uavsim:camera:uav0_down): k / 7 < 3 for
  // k = 0 .. 20; at 1 fps one in every 7 of those: k = 0, 7, 14
  ServerRun r = run_server(base + " --render-cameras uav0_down:grey");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_TRUE(
      has(r, "; 21 camera frames rendered for --render-cameras (uav0_down 21 at 7 fps grey)"))
      << r.output;
  r = run_server(base + " --render-cameras uav0_down@1,overview:rgb");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  // the world camera overview at its default 15 fps: k / 15 < 3 for k = 0 .. 44
  EXPECT_TRUE(has(r,
                  "; 48 camera frames rendered for --render-cameras (uav0_down 3 at 1 fps rgb, "
                  "overview 45 at 15 fps rgb)"))
      << r.output;
  // what only the world can say: exit code 2 before the clock starts, with what there is
  r = run_server(base + " --render-cameras uav0_front");
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_TRUE(has(r, "--render-cameras uav0_front: no such camera (cameras: overview, uav0_down)"))
      << r.output;
  r = run_server(base + " --render-cameras uav0_down@2");
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_TRUE(has(r, "the fps must be the camera's (7) divided by a whole number")) << r.output;
  r = run_server(base + " --render-cameras uav0_down:segmentation");
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_TRUE(has(r, "the camera gives no segmentation images")) << r.output;
  r = run_server("empty" + kWorlds +
                 " --duration 1 --rate 0 --api-port -1 --mavlink-port -1"
                 " --out none --render-cameras top");
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_TRUE(has(r, "--render-cameras top: no such camera")) << r.output;
  r = run_server(base + " --render-cameras uav0_down@0");
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_TRUE(has(r, "FPS needs frames per sim second from 0.001 to 1000")) << r.output;
}

TEST(ServerCli, VersionPrintsAndExitsZero) {
  const ServerRun r = run_server("--version");
  EXPECT_EQ(r.exit_code, 0);
  EXPECT_EQ(r.output.rfind("uavsim-server ", 0), 0u) << r.output;
}

TEST(ServerCli, BasePortTooHighForTheWorldsVehicles) {
  // grid100: vehicle 99 on 65000 + 990 = 65990
  const ServerRun r = run_server("grid100" + kWorlds +
                                 " --mavlink-port 65000 --api-port -1 --no-cameras --out none");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_TRUE(has(r, "65990")) << r.output;
  EXPECT_TRUE(has(r, "--mavlink-port 0")) << r.output;
}

TEST(ServerCli, UnknownWorldListsTheShippedWorlds) {
  const ServerRun r = run_server("mbzirc2099" + kWorlds);
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_TRUE(has(r, "no world file 'mbzirc2099'")) << r.output;
  EXPECT_TRUE(has(r, "mbzirc2020")) << r.output;
}

TEST(ServerCli, ListWorldsSaysWhereTheModelsAreAndExitsZero) {
  ServerRun r = run_server("--list-worlds" + kWorlds);
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_TRUE(has(r, std::string("# models: ") + UAVSIM_MODELS_DIR + " (--models-dir)"))
      << r.output;
  EXPECT_TRUE(has(r, "\nmbzirc2020 ")) << r.output;
  // the environment variable is the next place looked in; a folder without worlds/ fails
  r = run_server_env("UAVSIM_MODELS_DIR=/nonexistent", "--list-worlds");
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_TRUE(has(r, "# models: /nonexistent (UAVSIM_MODELS_DIR)")) << r.output;
}

TEST(ServerCli, PortInUseSuggestsEphemeralPorts) {
  // hold a TCP port, then ask the server for it
  const int fd = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  ASSERT_EQ(::bind(fd, reinterpret_cast<sockaddr*>(&a), sizeof(a)), 0);
  ASSERT_EQ(::listen(fd, 1), 0);
  socklen_t len = sizeof(a);
  ::getsockname(fd, reinterpret_cast<sockaddr*>(&a), &len);
  const int port = ntohs(a.sin_port);
  ServerRun r = run_server("empty" + kWorlds + " --mavlink-port " + std::to_string(port) +
                           " --api-port -1 --out none --duration 0.1 --rate 0");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_TRUE(has(r, "in use")) << r.output;
  EXPECT_TRUE(has(r, "--mavlink-port 0")) << r.output;
  r = run_server("empty" + kWorlds + " --api-port " + std::to_string(port) +
                 " --mavlink-port -1 --out none --duration 0.1 --rate 0 --no-cameras");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_TRUE(has(r, "--api-port 0")) << r.output;
  ::close(fd);
}

TEST(ServerCli, NonLoopbackApiBindWarns) {
  const ServerRun r =
      run_server("empty" + kWorlds +
                 " --api-bind 0.0.0.0 --api-port 0 --mavlink-port -1 --out none --no-cameras"
                 " --duration 0.05 --rate 0 --quiet");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_TRUE(has(r, "warning: --api-bind 0.0.0.0")) << r.output;
  EXPECT_TRUE(has(r, "no authentication")) << r.output;
}

TEST(ServerCli, DemoRunPrintsEventsAndASummary) {
  const ServerRun r =
      run_server("empty" + kWorlds + " --demo --rate 0 --api-port -1 --mavlink-port -1 --out none");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_TRUE(has(r, "uav0: armed")) << r.output;
  EXPECT_TRUE(has(r, "uav0: mode GUIDED")) << r.output;
  EXPECT_TRUE(has(r, "uav0: takeoff")) << r.output;
  EXPECT_TRUE(has(r, "uav0: disarmed")) << r.output;
  EXPECT_TRUE(has(r, "s of sim time in")) << r.output;
  EXPECT_TRUE(has(r, "0 crash(es)")) << r.output;
  const ServerRun quiet = run_server(
      "empty" + kWorlds + " --demo --rate 0 --api-port -1 --mavlink-port -1 --out none --quiet");
  EXPECT_EQ(quiet.exit_code, 0);
  EXPECT_FALSE(has(quiet, "uav0: armed")) << quiet.output;
  EXPECT_FALSE(has(quiet, "s of sim time in")) << quiet.output;
}

TEST(ServerCli, TheRadioBackendIsChosenAndNamedAtStart) {
  ServerRun r =
      run_server("empty" + kWorlds +
                 " --rate 0 --duration 0.1 --api-port 0 --mavlink-port -1 --out none --no-cameras");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_TRUE(has(r, "uavsim-server: radio: simple backend, frames of at most 127 bytes"))
      << r.output;
  r = run_server("empty --radio-backend tcp");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_TRUE(has(r, "--radio-backend needs simple or ns3")) << r.output;
  // an ns3 helper that cannot work ends the server at start with the reason, never a radio without
  // it (the server finds the helper through UAVSIM_NS3_RADIO first)
  setenv("UAVSIM_NS3_RADIO", "/bin/false", 1);
  r = run_server("empty" + kWorlds +
                 " --rate 0 --duration 0.1 --api-port 0 --mavlink-port -1 --out none --no-cameras "
                 "--radio-backend ns3");
  unsetenv("UAVSIM_NS3_RADIO");
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_TRUE(has(r, "uavsim-server: radio: ")) << r.output;
  EXPECT_TRUE(has(r, "the ns-3 radio helper failed")) << r.output;
  EXPECT_TRUE(has(r, "exited with status 1")) << r.output;
}

TEST(ServerCli, TheGcsLinkBackendAndPositionAreCheckedAndNamedAtStart) {
  const std::string run = "empty" + kWorlds +
                          " --rate 0 --duration 0.1 --api-port 0 --mavlink-port -1 --out none "
                          "--no-cameras ";
  ServerRun r = run_server("empty --gcs-link-backend wifi");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_TRUE(has(r, "--gcs-link-backend needs simple or ns3")) << r.output;
  for (const char* bad : {"1,2", "1,2,3,4", "1,nan,3", "1,2,100001", "1,,3"}) {
    r = run_server(run + "--gcs-position " + bad);
    EXPECT_EQ(r.exit_code, 2) << bad;
    EXPECT_TRUE(has(r, "--gcs-position needs X,Y,Z")) << r.output;
  }
  // the simple relay says nothing more; a helper that cannot work ends the server at start
  r = run_server(run + "--gcs-position 5,-3,2");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_FALSE(has(r, "gcs link:")) << r.output;
  setenv("UAVSIM_NS3_RADIO", "/bin/false", 1);
  r = run_server(run + "--gcs-link-backend ns3");
  unsetenv("UAVSIM_NS3_RADIO");
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_TRUE(has(r, "uavsim-server: gcs link: ")) << r.output;
  EXPECT_TRUE(has(r, "the ns-3 radio helper failed")) << r.output;
}

TEST(ServerCli, WaitForClientsHoldsTheClockUntilAClientConnects) {
  const std::string cmd =
      std::string(UAVSIM_SERVER_BIN) + " empty" + kWorlds +
      " --wait-for-clients 1 --rate 0 --duration 2 --mavlink-port 0 --api-port -1 --no-cameras"
      " 2>&1";
  FILE* p = popen(cmd.c_str(), "r");
  ASSERT_NE(p, nullptr);
  std::string output;
  int fd = -1;
  char line[4096];
  while (fgets(line, sizeof(line), p) != nullptr) {
    output += line;
    const std::string l = line;
    const auto at = l.find("MAVLink on tcp:127.0.0.1:");
    if (fd < 0 && at != std::string::npos) {
      // the server waits for this client before its clock starts
      const int port = std::stoi(l.substr(at + std::string("MAVLink on tcp:127.0.0.1:").size()));
      fd = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
      sockaddr_in a{};
      a.sin_family = AF_INET;
      a.sin_port = htons(static_cast<uint16_t>(port));
      a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
      ASSERT_EQ(::connect(fd, reinterpret_cast<sockaddr*>(&a), sizeof(a)), 0);
    }
  }
  const int status = pclose(p);
  if (fd >= 0) ::close(fd);
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << output;
  EXPECT_NE(output.find("waiting for 1 client(s)"), std::string::npos) << output;
  // the clock was still at 0 when the client's connection was handled
  EXPECT_NE(output.find("t=0.000 uav0: client_connected MAVLink tcp:127.0.0.1:"), std::string::npos)
      << output;
  EXPECT_NE(output.find("ran 2.000 s of sim time"), std::string::npos) << output;
}

// A server process with its output on a pipe, read line by line.
class ServerProcess {
 public:
  explicit ServerProcess(const std::vector<std::string>& args) {
    std::vector<std::string> argv{UAVSIM_SERVER_BIN};
    argv.insert(argv.end(), args.begin(), args.end());
    int fd = -1;
    pid_ = uavsim::testing::spawn_piped(std::move(argv), &fd);
    if (fd >= 0) out_ = fdopen(fd, "r");
  }
  ~ServerProcess() {
    if (pid_ > 0 && !reaped_) {
      kill(pid_, SIGKILL);
      waitpid(pid_, nullptr, 0);
    }
    if (out_ != nullptr) fclose(out_);
  }
  pid_t pid() const { return pid_; }
  // the lines up to and including the first that contains text ("" at end of output)
  std::string read_until(const std::string& text) {
    char line[4096];
    while (out_ != nullptr && fgets(line, sizeof(line), out_) != nullptr) {
      output_ += line;
      if (std::string(line).find(text) != std::string::npos) return line;
    }
    return "";
  }
  // the rest of the output, then the exit status (waitpid's)
  int wait_exit() {
    read_until("\x01never");
    int status = 0;
    waitpid(pid_, &status, 0);
    reaped_ = true;
    return status;
  }
  const std::string& output() const { return output_; }

 private:
  pid_t pid_ = -1;
  FILE* out_ = nullptr;
  std::string output_;
  bool reaped_ = false;
};

int connect_loopback(int port) {
  const int fd = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_port = htons(static_cast<uint16_t>(port));
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  if (::connect(fd, reinterpret_cast<sockaddr*>(&a), sizeof(a)) != 0) {
    ::close(fd);
    return -1;
  }
  return fd;
}

TEST(ServerCli, SigtermEndsAServerWhoseClockALockstepClientHolds) {
  // the clock waits for a lockstep client that never says done: SIGTERM still ends the server,
  // cleanly
  ServerProcess server({"empty", "--models-dir", UAVSIM_MODELS_DIR, "--rate", "0", "--mavlink-port",
                        "0", "--api-port", "0", "--no-cameras", "--lockstep-timeout", "86400"});
  ASSERT_GT(server.pid(), 0);
  const std::string api = server.read_until("sim API on tcp:127.0.0.1:");
  ASSERT_FALSE(api.empty()) << server.output();
  const int fd = connect_loopback(std::stoi(api.substr(api.rfind(':') + 1)));
  ASSERT_GE(fd, 0);
  const std::string join = "{\"op\":\"lockstep_join\",\"id\":1,\"period_s\":0.1}\n";
  ASSERT_EQ(::send(fd, join.data(), join.size(), MSG_NOSIGNAL), static_cast<ssize_t>(join.size()));
  // the reply and the first tick: from here the clock is held by this client
  std::string got;
  char buf[4096];
  while (got.find("\"tick\"") == std::string::npos) {
    const ssize_t n = ::recv(fd, buf, sizeof(buf), 0);
    ASSERT_GT(n, 0) << got;
    got.append(buf, static_cast<size_t>(n));
  }
  ASSERT_EQ(kill(server.pid(), SIGTERM), 0);
  const int status = server.wait_exit();
  ::close(fd);
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << status << "\n" << server.output();
  EXPECT_NE(server.output().find("ran "), std::string::npos) << server.output();
}

}  // namespace
