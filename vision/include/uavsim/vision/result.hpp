// An expected-like result type for the vision library: expected runtime failures are values, not
// exceptions (docs/development.md, "Code conventions"). C++20 has no std::expected yet.
#pragma once

#include <cassert>
#include <utility>
#include <variant>

namespace uavsim::vision {

template <typename T, typename E>
class Result {
 public:
  Result(T value) : v_(std::move(value)) {}  // NOLINT: implicit on purpose, like std::expected
  Result(E error) : v_(error) {}             // NOLINT

  bool ok() const { return v_.index() == 0; }
  explicit operator bool() const { return ok(); }

  // Precondition: ok().
  T& value() {
    assert(ok());
    return std::get<0>(v_);
  }
  const T& value() const {
    assert(ok());
    return std::get<0>(v_);
  }
  T& operator*() { return value(); }
  const T& operator*() const { return value(); }
  T* operator->() { return &value(); }
  const T* operator->() const { return &value(); }

  // Precondition: !ok().
  E error() const {
    assert(!ok());
    return std::get<1>(v_);
  }

 private:
  std::variant<T, E> v_;
};

// A result that carries no value on success.
template <typename E>
using Status = Result<std::monostate, E>;

}  // namespace uavsim::vision
