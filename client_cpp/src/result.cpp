// Result's out-of-line parts: the names of the error codes, and the abort of value() on a failure.
#include "uavsim/client/result.hpp"

#include <cstdio>
#include <cstdlib>

namespace uavsim::client {

const char* error_name(Error e) {
  switch (e) {
    case Error::kTimeout:
      return "timeout";
    case Error::kConnectionRefused:
      return "connection refused";
    case Error::kNotConnected:
      return "not connected";
    case Error::kConnectionLost:
      return "connection lost";
    case Error::kDenied:
      return "denied";
    case Error::kFailed:
      return "failed";
    case Error::kUnsupported:
      return "unsupported";
    case Error::kTemporarilyRejected:
      return "temporarily rejected";
    case Error::kCancelled:
      return "cancelled";
    case Error::kNotReady:
      return "not ready";
    case Error::kInvalidArgument:
      return "invalid argument";
    case Error::kIo:
      return "I/O error";
    case Error::kProtocol:
      return "protocol error";
  }
  return "?";
}

void abort_on_failure(const Failure& f) {
  std::fprintf(stderr, "uavsim client: value() of a failed Result: %s: %s\n", error_name(f.code),
               f.message.c_str());
  std::abort();
}

}  // namespace uavsim::client
