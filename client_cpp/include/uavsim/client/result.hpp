// Result<T>: the value of every client call that can fail. No exceptions: a failure is an Error code plus a
// human-readable message (and, for commands the vehicle refused, the MAV_RESULT it answered).
#pragma once

#include <cstdint>
#include <cstdlib>
#include <cstdio>
#include <optional>
#include <string>
#include <utility>
#include <variant>

namespace uavsim::client {

enum class Error {
  kTimeout,               // no answer in time (loop clock: sim time under lockstep)
  kConnectionRefused,     // nothing listens at the address
  kNotConnected,          // the link is down (never connected, closed, or lost)
  kConnectionLost,        // the link went down while waiting
  kDenied,                // the vehicle refused: MAV_RESULT_DENIED (2), or a refused mission/parameter
  kFailed,                // MAV_RESULT_FAILED (4)
  kUnsupported,           // MAV_RESULT_UNSUPPORTED (3)
  kTemporarilyRejected,   // MAV_RESULT_TEMPORARILY_REJECTED (1)
  kCancelled,             // MAV_RESULT_CANCELLED (6) or a transfer the vehicle cancelled
  kNotReady,              // the vehicle is not in a state that allows this (e.g. no home yet)
  kInvalidArgument,       // a bad argument (NaN, unknown mode, malformed address)
  kIo,                    // a system call failed (errno in the message)
  kProtocol,              // the peer answered something unexpected
};

// Stable name of an error ("timeout", "denied", ...).
const char* error_name(Error e);

struct Failure {
  Error code = Error::kFailed;
  std::string message;
  int mav_result = -1;  // the MAV_RESULT / MAV_MISSION_RESULT the vehicle answered; -1 if none
};

// Prints "Error: message" to stderr and aborts; used when value() is called on a failure.
[[noreturn]] void abort_on_failure(const Failure& f);

template <class T>
class [[nodiscard]] Result {
 public:
  Result(T value) : v_(std::in_place_index<0>, std::move(value)) {}  // NOLINT: implicit by design
  Result(Failure f) : v_(std::in_place_index<1>, std::move(f)) {}    // NOLINT
  static Result fail(Error code, std::string message, int mav_result = -1) {
    return Result(Failure{code, std::move(message), mav_result});
  }

  bool ok() const { return v_.index() == 0; }
  explicit operator bool() const { return ok(); }
  // The value; aborts with the message if this is a failure (check ok() first).
  const T& value() const& {
    if (!ok()) abort_on_failure(error());
    return std::get<0>(v_);
  }
  T& value() & {
    if (!ok()) abort_on_failure(error());
    return std::get<0>(v_);
  }
  T&& value() && {
    if (!ok()) abort_on_failure(error());
    return std::move(std::get<0>(v_));
  }
  const T& operator*() const& { return value(); }
  T& operator*() & { return value(); }
  const T* operator->() const { return &value(); }
  T* operator->() { return &value(); }
  T value_or(T fallback) const { return ok() ? std::get<0>(v_) : std::move(fallback); }
  // Only on a failure.
  const Failure& error() const { return std::get<1>(v_); }
  Error code() const { return error().code; }
  const std::string& message() const { return error().message; }

 private:
  std::variant<T, Failure> v_;
};

template <>
class [[nodiscard]] Result<void> {
 public:
  Result() = default;
  Result(Failure f) : f_(std::move(f)) {}  // NOLINT: implicit by design
  static Result fail(Error code, std::string message, int mav_result = -1) {
    return Result(Failure{code, std::move(message), mav_result});
  }
  template <class U>
  Result(const Result<U>& other) {  // NOLINT: forward the failure of another result (must be a failure)
    if (!other.ok()) f_ = other.error();
  }

  bool ok() const { return !f_.has_value(); }
  explicit operator bool() const { return ok(); }
  void value() const {
    if (!ok()) abort_on_failure(*f_);
  }
  const Failure& error() const { return *f_; }
  Error code() const { return f_->code; }
  const std::string& message() const { return f_->message; }

 private:
  std::optional<Failure> f_;
};

inline Result<void> ok() { return {}; }

}  // namespace uavsim::client
