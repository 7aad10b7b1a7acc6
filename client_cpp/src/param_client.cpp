// Parameter requests by name: each request is repeated every kResendS until the PARAM_VALUE for
// that name arrives (counted per name, so an answer to an older request also counts).
#include "param_client.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "uavsim/common/mavlink/generated/enums.hpp"
#include "uavsim/common/mavlink/generated/messages.hpp"
#include "uavsim/common/mavlink/wire.hpp"

namespace uavsim::client {

namespace mav = common::mavlink;
namespace msg = common::mavlink::msg;
using mav::to_underlying;

namespace {

constexpr double kResendS = 1.0;
constexpr std::size_t kMaxNameLength = 16;  // param_id is char[16]
constexpr std::int16_t kByName = -1;        // PARAM_REQUEST_READ.param_index: use param_id
// the vehicle's echo is the value set, up to float rounding
constexpr float kEchoRelTolerance = 1e-6f;

bool valid_name(const std::string& name) { return !name.empty() && name.size() <= kMaxNameLength; }

}  // namespace

ParamClient::ParamClient(EventLoop& loop, MavPort& port) : loop_(loop), port_(port) {
  port_.on_message(msg::ParamValue::kId, [this](const mav::Frame& f) {
    const auto m = msg::ParamValue::decode(f.payload.data());
    Seen& p = seen_[std::string(mav::get_string(m.param_id))];
    p.value = m.param_value;
    p.type = m.param_type;
    ++p.count;
  });
}

template <class Request>
bool ParamClient::ask(const std::string& name, const Request& request, double timeout_s) {
  const std::uint64_t before = seen_[name].count;
  const double deadline = loop_.now() + timeout_s;
  while (loop_.now() < deadline && port_.is_open()) {
    port_.send(request);
    (void)loop_.run_until([&] { return seen_[name].count > before || !port_.is_open(); },
                          std::min(kResendS, deadline - loop_.now()), "PARAM_VALUE");
    if (seen_[name].count > before) return true;
  }
  return false;
}

Result<float> ParamClient::get(const std::string& name, double timeout_s) {
  loop_.assert_in_loop_thread();
  if (auto r = port_.need_open(); !r) return Result<float>(r.error());
  if (!valid_name(name)) {
    return Result<float>::fail(Error::kInvalidArgument, "parameter names have 1-16 characters");
  }
  msg::ParamRequestRead rq;
  rq.target_system = port_.target_sysid();
  rq.target_component = port_.target_compid();
  rq.param_index = kByName;
  mav::set_string(rq.param_id, name);
  if (ask(name, rq, timeout_s)) return seen_[name].value;
  if (!port_.is_open()) {
    return Result<float>::fail(Error::kConnectionLost, "get " + name + ": the link was lost");
  }
  return Result<float>::fail(Error::kTimeout, "no PARAM_VALUE for " + name + " within " +
                                                  std::to_string(timeout_s) +
                                                  " s (unknown parameter?)");
}

Result<float> ParamClient::set(const std::string& name, float value, double timeout_s) {
  loop_.assert_in_loop_thread();
  if (auto r = port_.need_open(); !r) return Result<float>(r.error());
  if (!valid_name(name)) {
    return Result<float>::fail(Error::kInvalidArgument, "parameter names have 1-16 characters");
  }
  if (!std::isfinite(value)) {
    return Result<float>::fail(Error::kInvalidArgument, "parameter values must be finite");
  }
  const Seen& known = seen_[name];
  msg::ParamSet ps;
  ps.target_system = port_.target_sysid();
  ps.target_component = port_.target_compid();
  mav::set_string(ps.param_id, name);
  ps.param_value = value;
  ps.param_type = known.count > 0 ? known.type : to_underlying(mav::MavParamType::Real32);
  if (ask(name, ps, timeout_s)) {
    const float got = seen_[name].value;
    if (std::abs(got - value) > kEchoRelTolerance * std::max(1.0f, std::abs(value))) {
      std::ostringstream os;
      os << "set " << name << " = " << value << ": the vehicle kept " << got;
      return Result<float>::fail(Error::kDenied, os.str());
    }
    return got;
  }
  if (!port_.is_open()) {
    return Result<float>::fail(Error::kConnectionLost, "set " + name + ": the link was lost");
  }
  return Result<float>::fail(Error::kTimeout, "no PARAM_VALUE echo for " + name + " within " +
                                                  std::to_string(timeout_s) +
                                                  " s (unknown parameter?)");
}

}  // namespace uavsim::client
