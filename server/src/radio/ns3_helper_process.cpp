// The ns3 backend's helper process (ns3_channel.hpp): where the program is, spawning it on a
// socket pair, one request and its reply with a wall-time limit, and ending it when it fails or
// the channel goes away. Kept apart from the channel's radio logic (ns3_channel.cpp).
#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <stdexcept>
#include <thread>

#include "radio/ns3_channel.hpp"
#include "wire.hpp"

extern char** environ;

namespace uavsim::server::radio {

namespace {

namespace wire = uavsim::ns3wire;

constexpr int kHelperFd = 3;  // the helper's end of the socket pair

// the wait status of a helper that is gone, in words
std::string exit_words(int status) {
  if (WIFEXITED(status)) return "exited with status " + std::to_string(WEXITSTATUS(status));
  if (WIFSIGNALED(status)) return "was killed by signal " + std::to_string(WTERMSIG(status));
  return "stopped";
}

}  // namespace

std::optional<std::string> find_ns3_helper() {
  namespace fs = std::filesystem;
  std::error_code ec;
  if (const char* env = std::getenv("UAVSIM_NS3_RADIO"); env != nullptr && *env != '\0') {
    return std::string(env);
  }
  const fs::path self = fs::read_symlink("/proc/self/exe", ec);
  if (!ec) {
    const fs::path beside = self.parent_path() / "uavsim-ns3-radio";
    if (fs::is_regular_file(beside, ec)) return beside.string();
  }
#ifdef UAVSIM_NS3_HELPER_PATH
  if (fs::is_regular_file(UAVSIM_NS3_HELPER_PATH, ec)) return std::string(UAVSIM_NS3_HELPER_PATH);
#endif
  return std::nullopt;
}

Ns3Channel::~Ns3Channel() {
  // a step sent ahead is answered first: the helper reads its quit only after writing that answer
  collect();
  if (fd_ >= 0 && failure_.empty()) {
    wire::Writer w;
    w.put(static_cast<uint8_t>(wire::MessageType::kQuit));
    wire::write_all(fd_, w.message());
  }
  if (fd_ >= 0) ::close(fd_);
  if (pid_ > 0) {
    // the helper exits when asked or when its socket closes; a hung one is killed after 2 s
    int status = 0;
    for (int k = 0; k < 200; ++k) {
      if (::waitpid(pid_, &status, WNOHANG) != 0) return;
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    ::kill(pid_, SIGKILL);
    ::waitpid(pid_, &status, 0);
  }
}

void Ns3Channel::spawn() {
  if (options_.helper_path.empty()) {
    throw std::runtime_error(
        "radio (ns3 backend): no uavsim-ns3-radio program (build with ns-3 installed: "
        "scripts/install_deps.sh; or set UAVSIM_NS3_RADIO)");
  }
  int sv[2];
  if (::socketpair(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0, sv) != 0) {
    throw std::runtime_error(std::string("radio (ns3 backend): socketpair: ") +
                             std::strerror(errno));
  }
  // the child's end becomes its fd 3 (dup2 clears close-on-exec there; if it already is 3, clear
  // it)
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  if (sv[1] == kHelperFd) {
    ::fcntl(sv[1], F_SETFD, 0);
  } else {
    posix_spawn_file_actions_adddup2(&actions, sv[1], kHelperFd);
  }
  const std::string fd_text = std::to_string(kHelperFd);
  std::vector<char*> argv = {const_cast<char*>(options_.helper_path.c_str()),
                             const_cast<char*>("--fd"), const_cast<char*>(fd_text.c_str()),
                             nullptr};
  const int rc =
      ::posix_spawn(&pid_, options_.helper_path.c_str(), &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  ::close(sv[1]);
  if (rc != 0) {
    ::close(sv[0]);
    pid_ = -1;
    throw std::runtime_error("radio (ns3 backend): cannot start " + options_.helper_path + ": " +
                             std::strerror(rc));
  }
  fd_ = sv[0];
}

void Ns3Channel::fail(const std::string& why, bool hung) {
  if (!failure_.empty()) return;
  std::string what = why;
  if (pid_ > 0) {
    // a helper whose socket closed is exiting: wait (up to 1 s) to say how it ended; a hung one,
    // or one that does not exit, is ended here
    int status = 0;
    pid_t r = 0;
    for (int k = 0; !hung && r == 0 && k < 100; ++k) {
      r = ::waitpid(pid_, &status, WNOHANG);
      if (r == 0) std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    if (r == pid_) {
      what += " (uavsim-ns3-radio " + exit_words(status) + ")";
    } else {
      ::kill(pid_, SIGKILL);
      ::waitpid(pid_, &status, 0);
      what += " (ended it)";
    }
    pid_ = -1;
  }
  failure_ = "the ns-3 radio helper failed: " + what;
  busy_ = false;
}

bool Ns3Channel::exchange(const std::vector<uint8_t>& request, std::vector<uint8_t>* reply) {
  return send_request(request) && read_reply(reply);
}

bool Ns3Channel::send_request(const std::vector<uint8_t>& request) {
  if (!failure_.empty()) return false;
  const wire::IoResult r = wire::write_all(fd_, request);
  if (r != wire::IoResult::kOk) {
    fail(std::string("sending to it: ") + wire::io_result_name(r));
    return false;
  }
  return true;
}

bool Ns3Channel::read_reply(std::vector<uint8_t>* reply) {
  if (!failure_.empty()) return false;
  const int timeout_ms = static_cast<int>(std::lround(options_.reply_timeout_s * 1000.0));
  const wire::IoResult r = wire::read_message(fd_, timeout_ms, reply);
  if (r != wire::IoResult::kOk) {
    const bool hung = r == wire::IoResult::kTimeout;
    fail(std::string("waiting for its answer: ") + wire::io_result_name(r) +
             (hung ? " (" + std::to_string(options_.reply_timeout_s) + " s)" : std::string()),
         hung);
    return false;
  }
  if (!reply->empty() && (*reply)[0] == static_cast<uint8_t>(wire::MessageType::kError)) {
    wire::Reader in(reply->data() + 1, reply->size() - 1);
    const auto n = in.get<uint16_t>();
    std::vector<uint8_t> text;
    in.bytes(n, &text);
    fail("it reported: " + std::string(text.begin(), text.end()));
    return false;
  }
  return true;
}

}  // namespace uavsim::server::radio
