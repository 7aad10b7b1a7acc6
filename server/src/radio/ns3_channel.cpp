#include "radio/ns3_channel.hpp"

#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <stdexcept>
#include <thread>

#include "radio/radio_model.hpp"
#include "wire.hpp"

extern char** environ;

namespace uavsim::server::radio {

namespace {

namespace wire = uavsim::ns3wire;

constexpr double kTimeEps = 1e-9;
constexpr size_t kNs3MacHeaderBytes = 11;    // short addresses, compressed PAN id, FCS
constexpr double kLrWpanFloorDbm = -106.58;  // lr-wpan 3.37's fixed receiver sensitivity
constexpr int kHelperFd = 3;                 // the helper's end of the socket pair
constexpr double kObstacleLossChangeDb = 1e-9;

wire::Channel wire_channel(const RadioConfig& c) {
  wire::Channel w;
  w.log_distance = c.propagation == Propagation::kLogDistance ? 1 : 0;
  w.range_m = c.range_m;
  w.tx_power_dbm = c.tx_power_dbm;
  w.sensitivity_dbm = c.sensitivity_dbm;
  w.reference_loss_db = c.reference_loss_db;
  w.path_loss_exponent = c.path_loss_exponent;
  w.shadowing_sigma_db = c.shadowing_sigma_db;
  return w;
}

bool same_channel(const RadioConfig& a, const RadioConfig& b) {
  return a.propagation == b.propagation && a.range_m == b.range_m &&
         a.tx_power_dbm == b.tx_power_dbm && a.sensitivity_dbm == b.sensitivity_dbm &&
         a.reference_loss_db == b.reference_loss_db &&
         a.path_loss_exponent == b.path_loss_exponent &&
         a.shadowing_sigma_db == b.shadowing_sigma_db;
}

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

std::string Ns3Channel::validate_ns3(const RadioConfig& c) {
  // the rules both backends share (finite numbers, ranges), then what lr-wpan fixes
  RadioConfig shared = c;
  shared.mac_header_bytes = 0;
  const std::string why = validate(shared, 1);
  if (!why.empty()) return why;
  if (c.tdma) return "tdma is not available on the ns3 backend (lr-wpan runs unslotted CSMA-CA)";
  if (c.loss_probability != 0.0) {
    return "loss must be 0 on the ns3 backend (ns-3 loses frames by SINR, not by a draw)";
  }
  if (!c.collisions) return "collisions are always modelled on the ns3 backend";
  if (c.mac_header_bytes != kNs3MacHeaderBytes) {
    return "mac_header_bytes is " + std::to_string(kNs3MacHeaderBytes) +
           " on the ns3 backend (short addresses, compressed PAN id, FCS)";
  }
  if (c.sensitivity_dbm < kLrWpanFloorDbm) {
    return "sensitivity_dbm must be >= -106.58 on the ns3 backend (lr-wpan's own floor in ns-3 "
           "3.37)";
  }
  return "";
}

Ns3Channel::Ns3Channel(size_t vehicles, const RadioConfig& config, uint64_t seed, double step_s,
                       const Ns3Options& options)
    : vehicles_(vehicles), config_(config), step_s_(step_s), options_(options) {
  // what ns-3 always does, whatever the simple model's defaults say
  config_.mac_header_bytes = kNs3MacHeaderBytes;
  config_.collisions = true;
  const std::string why = validate_ns3(config_);
  if (!why.empty()) throw std::invalid_argument("radio config (ns3 backend): " + why);
  if (!(step_s > 0.0)) throw std::invalid_argument("radio: step_s must be > 0");
  if (vehicles == 0 || vehicles > wire::kMaxVehicles) {
    throw std::invalid_argument("radio (ns3 backend): needs 1 to " +
                                std::to_string(wire::kMaxVehicles) + " vehicles");
  }
  if (!(options.reply_timeout_s > 0.0 && options.reply_timeout_s <= 3600.0)) {
    throw std::invalid_argument("radio (ns3 backend): reply timeout must be in (0, 3600] s");
  }
  velocities_enu_m_s_.assign(vehicles, Eigen::Vector3d::Zero());
  spawn();
  wire::Writer w;
  w.put(static_cast<uint8_t>(wire::MessageType::kInit));
  w.put(static_cast<uint32_t>(vehicles));
  w.put(seed);
  wire::put_channel(w, wire_channel(config_));
  if (!expect_ready(w.message())) {
    // no destructor runs for a constructor that throws: fail() has reaped the helper, close its
    // socket
    ::close(fd_);
    fd_ = -1;
    throw std::runtime_error("radio (ns3 backend): " + failure_);
  }
  reset_state();
}

Ns3Channel::~Ns3Channel() {
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
  if (!failure_.empty()) return false;
  wire::IoResult r = wire::write_all(fd_, request);
  if (r != wire::IoResult::kOk) {
    fail(std::string("sending to it: ") + wire::io_result_name(r));
    return false;
  }
  const int timeout_ms = static_cast<int>(std::lround(options_.reply_timeout_s * 1000.0));
  r = wire::read_message(fd_, timeout_ms, reply);
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

bool Ns3Channel::expect_ready(const std::vector<uint8_t>& request) {
  std::vector<uint8_t> reply;
  if (!exchange(request, &reply)) return false;
  wire::Reader in(reply.data(), reply.size());
  const auto type = in.get<uint8_t>();
  const auto max_payload = in.get<uint32_t>();
  if (!in.ok() || type != static_cast<uint8_t>(wire::MessageType::kReady) || max_payload == 0 ||
      max_payload > kMaxFrameBytes) {
    fail("a malformed ready answer");
    return false;
  }
  max_payload_bytes_ = max_payload;
  return true;
}

void Ns3Channel::reset_state() {
  helper_ns_ = 0;
  busy_ = false;
  queue_.clear();
  next_seq_.assign(vehicles_, 0);
  queued_.assign(vehicles_, 0);
  in_flight_.assign(vehicles_, 0);
  pushed_loss_db_.assign(vehicles_ * vehicles_, 0.0);
  pending_.clear();
  links_.assign(vehicles_ * vehicles_, LinkStats{});
  transmitted_.assign(vehicles_, 0);
  access_failures_.assign(vehicles_, 0);
}

void Ns3Channel::reset(uint64_t seed) {
  if (!failure_.empty()) return;
  wire::Writer w;
  w.put(static_cast<uint8_t>(wire::MessageType::kReset));
  w.put(seed);
  expect_ready(w.message());
  reset_state();
}

bool Ns3Channel::set_config(const RadioConfig& config, std::string* error) {
  const std::string why = validate_ns3(config);
  if (!why.empty()) {
    if (error != nullptr) *error = why;
    return false;
  }
  if (!same_channel(config, config_) && failure_.empty()) {
    wire::Writer w;
    w.put(static_cast<uint8_t>(wire::MessageType::kConfig));
    wire::put_channel(w, wire_channel(config));
    if (!expect_ready(w.message())) {
      if (error != nullptr) *error = failure_;
      return false;
    }
  }
  config_ = config;
  return true;
}

int64_t Ns3Channel::to_ns(double t_s) const { return std::llround(t_s * 1e9); }

SendResult Ns3Channel::send(size_t from, int to, const std::vector<uint8_t>& data, double now_s) {
  SendResult r;
  if (from >= vehicles_ || (to != kBroadcast && (to < 0 || static_cast<size_t>(to) >= vehicles_))) {
    r.error = Error::kUnknownVehicle;
  } else if (to == static_cast<int>(from)) {
    r.error = Error::kBadDestination;
  } else if (data.empty()) {
    r.error = Error::kEmptyFrame;
  } else if (data.size() > max_payload_bytes_) {
    r.error = Error::kFrameTooLarge;
  } else if (!failure_.empty() || queued(from) >= config_.max_queue_frames) {
    // a failed helper takes nothing more (the run is ending)
    r.error = Error::kQueueFull;
  } else {
    Queued q;
    q.from = from;
    q.to = to;
    q.seq = next_seq_[from]++;
    q.queued_ns = to_ns(now_s);
    q.data = data;
    queue_.push_back(std::move(q));
    ++queued_[from];
    r.seq = queue_.back().seq;
  }
  return r;
}

bool Ns3Channel::has_due(double now_s) const {
  (void)now_s;
  return failure_.empty() && (!queue_.empty() || busy_);
}

void Ns3Channel::set_velocities(const std::vector<Eigen::Vector3d>& velocities_enu_m_s) {
  if (velocities_enu_m_s.size() == vehicles_) velocities_enu_m_s_ = velocities_enu_m_s;
}

void Ns3Channel::step(double now_s, const std::vector<Eigen::Vector3d>& positions_enu_m,
                      std::vector<Delivery>* out, bool starting_now) {
  const int64_t now_ns = to_ns(now_s);
  // frames to hand over: those sent by now (with starting_now false, those sent before now: a
  // lockstep client may still send for now), in (time, sender, seq) order: the order ns-3's
  // MACs get them, whatever order the requests came in
  std::vector<Queued> hand;
  auto due = [&](const Queued& q) {
    return starting_now ? q.queued_ns <= now_ns : q.queued_ns < now_ns;
  };
  for (auto it = queue_.begin(); it != queue_.end();) {
    if (due(*it)) {
      hand.push_back(std::move(*it));
      it = queue_.erase(it);
    } else {
      ++it;
    }
  }
  std::stable_sort(hand.begin(), hand.end(), [](const Queued& a, const Queued& b) {
    if (a.queued_ns != b.queued_ns) return a.queued_ns < b.queued_ns;
    if (a.from != b.from) return a.from < b.from;
    return a.seq < b.seq;
  });
  const bool advance = busy_ && now_ns > helper_ns_;
  if (failure_.empty() && (!hand.empty() || advance) && now_ns >= helper_ns_ &&
      positions_enu_m.size() == vehicles_) {
    wire::Writer w;
    w.put(static_cast<uint8_t>(wire::MessageType::kStep));
    w.put(now_ns);
    w.put<uint8_t>(1);
    for (size_t i = 0; i < vehicles_; ++i) {
      for (int k = 0; k < 3; ++k) w.put(positions_enu_m[i][k]);
      for (int k = 0; k < 3; ++k) w.put(velocities_enu_m_s_[i][k]);
    }
    // obstacle losses of the links this step's senders use (both ways: ACKs come back)
    std::vector<size_t> senders;
    for (const Queued& q : hand) senders.push_back(q.from);
    std::sort(senders.begin(), senders.end());
    senders.erase(std::unique(senders.begin(), senders.end()), senders.end());
    wire::Writer losses;
    uint32_t loss_count = 0;
    for (size_t s : senders) {
      for (size_t r = 0; r < vehicles_; ++r) {
        if (r == s) continue;
        const double db = link_loss_db(s, r);
        for (const auto& [a, b] : {std::pair{s, r}, std::pair{r, s}}) {
          double& pushed = pushed_loss_db_[a * vehicles_ + b];
          if (std::abs(pushed - db) <= kObstacleLossChangeDb) continue;
          pushed = db;
          losses.put(static_cast<uint32_t>(a));
          losses.put(static_cast<uint32_t>(b));
          losses.put(db);
          ++loss_count;
        }
      }
    }
    w.put(loss_count);
    const std::vector<uint8_t> loss_bytes = losses.message();
    w.bytes(loss_bytes.data() + 4, loss_bytes.size() - 4);
    w.put(static_cast<uint32_t>(hand.size()));
    for (const Queued& q : hand) {
      w.put(static_cast<uint32_t>(q.from));
      w.put(static_cast<int32_t>(q.to));
      w.put(q.seq);
      w.put(q.queued_ns);
      w.put(static_cast<uint16_t>(q.data.size()));
      w.bytes(q.data.data(), q.data.size());
      --queued_[q.from];
      ++in_flight_[q.from];
    }
    std::vector<uint8_t> reply;
    if (exchange(w.message(), &reply) && !read_step_done(reply)) fail("a malformed step answer");
    helper_ns_ = now_ns;
  } else {
    for (const Queued& q : hand) --queued_[q.from];  // a failed helper: dropped
  }

  // arrivals up to now, in (time, receiver, sender, seq) order
  take_arrivals(&pending_, now_s, out);
}

bool Ns3Channel::read_step_done(const std::vector<uint8_t>& reply) {
  wire::Reader in(reply.data(), reply.size());
  if (in.get<uint8_t>() != static_cast<uint8_t>(wire::MessageType::kStepDone)) return false;
  in.get<int64_t>();
  const bool busy = in.get<uint8_t>() != 0;
  // receptions: they arrive after the processing latency, and never before one step after they
  // were sent (as on the simple backend)
  const auto deliveries = in.get<uint32_t>();
  if (!in.ok() || deliveries > in.left() / 45) return false;
  for (uint32_t k = 0; k < deliveries; ++k) {
    Delivery d;
    const auto to = in.get<uint32_t>();
    const auto from = in.get<uint32_t>();
    d.seq = in.get<uint64_t>();
    d.broadcast = in.get<uint8_t>() != 0;
    const auto queued_ns = in.get<int64_t>();
    const auto tx_start_ns = in.get<int64_t>();
    const auto rx_ns = in.get<int64_t>();
    in.get<uint8_t>();  // LQI
    const auto n = in.get<uint16_t>();
    if (!in.ok() || to >= vehicles_ || from >= vehicles_ || n == 0 || n > kMaxFrameBytes ||
        !in.bytes(n, &d.data)) {
      return false;
    }
    d.to = to;
    d.from = from;
    d.queued_s = static_cast<double>(queued_ns) * 1e-9;
    d.tx_start_s = static_cast<double>(tx_start_ns) * 1e-9;
    d.time_s =
        std::max(static_cast<double>(rx_ns) * 1e-9 + config_.latency_s, d.queued_s + step_s_);
    pending_.push_back(std::move(d));
  }
  const auto confirms = in.get<uint32_t>();
  if (!in.ok() || confirms > in.left() / 13) return false;
  for (uint32_t k = 0; k < confirms; ++k) {
    const auto from = in.get<uint32_t>();
    in.get<uint64_t>();
    in.get<uint8_t>();
    if (!in.ok() || from >= vehicles_ || in_flight_[from] == 0) return false;
    --in_flight_[from];
  }
  const auto counters = in.get<uint32_t>();
  if (!in.ok() || counters > in.left() / 9) return false;
  for (uint32_t k = 0; k < counters; ++k) {
    const auto from = in.get<uint32_t>();
    const auto to = in.get<uint32_t>();
    const auto kind = static_cast<wire::Counter>(in.get<uint8_t>());
    if (!in.ok() || from >= vehicles_ || to >= vehicles_) return false;
    LinkStats& s = links_[from * vehicles_ + to];
    switch (kind) {
      case wire::Counter::kSent:
        ++s.sent;
        break;
      case wire::Counter::kDelivered:
        ++s.delivered;
        break;
      case wire::Counter::kLost:
        ++s.lost;
        break;
      case wire::Counter::kOutOfRange:
        ++s.out_of_range;
        break;
      case wire::Counter::kNoAck:
        ++s.no_ack;
        break;
      case wire::Counter::kTransmitted:
        ++transmitted_[from];
        break;
      case wire::Counter::kChannelAccessFailure:
        ++access_failures_[from];
        break;
      default:
        return false;
    }
  }
  busy_ = busy;
  return in.ok() && in.left() == 0;
}

}  // namespace uavsim::server::radio
