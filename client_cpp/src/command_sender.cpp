// One retry machine for COMMAND_LONG (see command_sender.hpp): per-command state keyed by the
// command id, a retry timer per attempt, and the ack's MAV_RESULT mapped onto the client's Error.
#include "command_sender.hpp"

#include <algorithm>
#include <limits>
#include <memory>
#include <optional>
#include <sstream>

#include "uavsim/common/mavlink/generated/enum_names.hpp"
#include "uavsim/common/mavlink/generated/messages.hpp"

namespace uavsim::client {

namespace mav = common::mavlink;
namespace msg = common::mavlink::msg;
using mav::MavResult;

namespace {

Error error_of_mav_result(MavResult r) {
  switch (r) {
    case MavResult::TemporarilyRejected:
      return Error::kTemporarilyRejected;
    case MavResult::Denied:
      return Error::kDenied;
    case MavResult::Unsupported:
      return Error::kUnsupported;
    case MavResult::Cancelled:
      return Error::kCancelled;
    default:
      return Error::kFailed;
  }
}

// the outcome of a final COMMAND_ACK (any result but IN_PROGRESS)
Result<void> ack_outcome(std::uint16_t command, std::uint8_t result) {
  const auto r = static_cast<MavResult>(result);
  if (r == MavResult::Accepted) return {};
  const std::string_view name = mav::enum_name(r);
  return Result<void>::fail(error_of_mav_result(r),
                            command_name(command) + " refused by the vehicle: MAV_RESULT_" +
                                std::string(name.empty() ? "UNKNOWN" : name) + " (" +
                                std::to_string(result) + ")",
                            result);
}

Result<void> link_lost(std::uint16_t command) {
  return Result<void>::fail(Error::kConnectionLost, command_name(command) + ": the link was lost");
}

}  // namespace

std::string command_name(std::uint16_t command) {
  const std::string_view name = mav::enum_name(static_cast<mav::MavCmd>(command));
  return name.empty() ? "MAV_CMD " + std::to_string(command) : std::string(name);
}

CommandSender::CommandSender(EventLoop& loop, MavPort& port, const VehicleConfig& config)
    : loop_(loop), port_(port), config_(config) {
  port_.on_message(msg::CommandAck::kId, [this](const mav::Frame& f) { on_ack(f); });
}

CommandSender::~CommandSender() { drop_all(); }

void CommandSender::send_async(std::uint16_t command, const Params& params, Done done) {
  loop_.assert_in_loop_thread();
  if (auto r = port_.need_open(); !r) {
    if (done) loop_.post([done = std::move(done), r] { done(r); });
    return;
  }
  finish(command, Result<void>::fail(Error::kCancelled,
                                     command_name(command) + ": replaced by a newer one"));
  Pending& p = pending_[command];
  p.params = params;
  p.done = std::move(done);
  p.serial = next_serial_++;
  transmit(command);
}

Result<void> CommandSender::send(std::uint16_t command, const Params& params) {
  loop_.assert_in_loop_thread();
  if (auto r = port_.need_open(); !r) return r;
  // shared with the done: a done already posted when the wait gives up still has it
  auto outcome = std::make_shared<std::optional<Result<void>>>();
  const std::uint64_t serial = next_serial_;
  send_async(command, params, [outcome](Result<void> r) { *outcome = std::move(r); });
  // the retry machine always ends the command: the wait needs no deadline of its own
  auto w = loop_.run_until([&] { return outcome->has_value(); },
                           std::numeric_limits<double>::infinity(), "COMMAND_ACK");
  if (outcome->has_value()) return **outcome;
  // the loop cannot wait any more (the lockstep clock is lost): the command is abandoned (unless
  // a newer one with the same id has replaced it meanwhile)
  if (auto it = pending_.find(command); it != pending_.end() && it->second.serial == serial) {
    if (it->second.retry != 0) loop_.cancel(it->second.retry);
    pending_.erase(it);
  }
  return w;
}

Result<void> CommandSender::send(mav::MavCmd command, const Params& params) {
  return send(static_cast<std::uint16_t>(mav::to_underlying(command)), params);
}

void CommandSender::send_async(mav::MavCmd command, const Params& params, Done done) {
  send_async(static_cast<std::uint16_t>(mav::to_underlying(command)), params, std::move(done));
}

void CommandSender::transmit(std::uint16_t command) {
  const Pending& p = pending_.at(command);
  msg::CommandLong c;
  c.target_system = port_.target_sysid();
  c.target_component = port_.target_compid();
  c.command = command;
  c.confirmation = static_cast<std::uint8_t>(std::min(p.attempt, 255));
  c.param1 = p.params[0], c.param2 = p.params[1], c.param3 = p.params[2], c.param4 = p.params[3];
  c.param5 = p.params[4], c.param6 = p.params[5], c.param7 = p.params[6];
  if (!port_.send(c)) {
    finish(command, link_lost(command));
    return;
  }
  arm_retry(command);
}

void CommandSender::arm_retry(std::uint16_t command) {
  Pending& p = pending_.at(command);
  if (p.retry != 0) loop_.cancel(p.retry);
  p.retry = loop_.call_after(config_.command_timeout_s, [this, command] {
    auto it = pending_.find(command);
    if (it == pending_.end()) return;
    it->second.retry = 0;
    if (++it->second.attempt < std::max(1, config_.command_attempts)) {
      transmit(command);
      return;
    }
    finish(command, no_ack(command));
  });
}

void CommandSender::on_ack(const mav::Frame& f) {
  const auto m = msg::CommandAck::decode(f.payload.data());
  // an ack for another ground station on the same link
  if (m.target_system != 0 && m.target_system != config_.gcs_sysid) return;
  if (pending_.count(m.command) == 0) return;
  if (m.result == mav::to_underlying(MavResult::InProgress)) {  // the final ack follows
    arm_retry(m.command);
    return;
  }
  finish(m.command, ack_outcome(m.command, m.result));
}

void CommandSender::finish(std::uint16_t command, Result<void> outcome) {
  auto it = pending_.find(command);
  if (it == pending_.end()) return;
  if (it->second.retry != 0) loop_.cancel(it->second.retry);
  auto done = std::move(it->second.done);
  pending_.erase(it);
  if (done) loop_.post([done = std::move(done), outcome = std::move(outcome)] { done(outcome); });
}

void CommandSender::fail_all(const std::string& why) {
  while (!pending_.empty()) {
    const std::uint16_t command = pending_.begin()->first;
    finish(command, Result<void>::fail(Error::kConnectionLost, command_name(command) + ": " + why));
  }
}

void CommandSender::drop_all() {
  for (auto& [command, p] : pending_) {
    if (p.retry != 0) loop_.cancel(p.retry);
  }
  pending_.clear();
}

Result<void> CommandSender::no_ack(std::uint16_t command) const {
  std::ostringstream os;
  os << "no COMMAND_ACK for " << command_name(command) << " after "
     << std::max(1, config_.command_attempts) << " attempt(s) of " << config_.command_timeout_s
     << " s";
  return Result<void>::fail(Error::kTimeout, os.str());
}

}  // namespace uavsim::client
