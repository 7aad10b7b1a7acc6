// What the binding units of uavsim._core share: failures raised as Python exceptions, JSON <->
// Python, Python callbacks run from the event loop, and blocking calls that release the GIL.
//
// The GIL: every call that waits (a blocking Vehicle command, EventLoop.run_for, a SimConnection
// request) releases it, so other Python threads run meanwhile; the loop's callbacks into Python
// (telemetry, frames, timers) take it back for the call. A callback that raises does not unwind
// through the C++ loop: its exception is kept and raised by the blocking call during which it ran,
// once that call returns.
#pragma once

#include <pybind11/pybind11.h>

#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <utility>

#include "uavsim/client/result.hpp"

namespace uavsim::python {

namespace py = pybind11;
using client::Error;
using client::Failure;
using client::Result;

// Registers the exception classes on the module: UavsimError(RuntimeError) with .code (Error),
// .mav_result and .message, and its subclasses InvalidArgumentError (also ValueError), TimeoutError
// (also the built-in TimeoutError) and ConnectionError (also the built-in ConnectionError).
void register_errors(py::module_& m);
// Raises the failure as the exception class its code maps to. Needs the GIL.
[[noreturn]] void raise_failure(const Failure& f);

// A duration or delay from Python: finite and not negative (infinite only where allowed), else
// InvalidArgumentError naming the argument. Needs the GIL.
double checked_duration(double v, const char* name, bool allow_infinite = false);
// A TCP port from Python: 1..65535, else InvalidArgumentError. Needs the GIL.
int checked_port(int port);

// The value of a result, or its failure raised. Needs the GIL.
template <class T>
T unwrap(Result<T>&& r) {
  if (!r.ok()) raise_failure(r.error());
  return std::move(r).value();
}
inline void unwrap(Result<void>&& r) {
  if (!r.ok()) raise_failure(r.error());
}

// JSON value -> Python (dict, list, str, int, float, bool, None) and back. from_python accepts what
// the json module would (str keys only), plus numpy scalars and arrays (through their tolist());
// anything else is a TypeError. Both need the GIL.
py::object to_python(const nlohmann::json& j);
nlohmann::json from_python(py::handle h);

// The first exception raised by a Python callback since the last check, kept for the blocking call
// the callback ran in. Only touched with the GIL held.
class CallbackErrors {
 public:
  // Runs fn (a call into Python, GIL held); keeps its exception if it raised, and writes any later
  // one of the same blocking call to sys.unraisablehook (it cannot be raised twice). Nothing is
  // thrown out of it: a C++ exception (a failed conversion, ...) becomes a Python one.
  template <class F>
  void guard(F&& fn) {
    try {
      fn();
    } catch (py::error_already_set& e) {
      keep(std::move(e));
    } catch (py::builtin_exception& e) {
      e.set_error();
      keep(py::error_already_set());
    } catch (const std::exception& e) {
      PyErr_SetString(PyExc_RuntimeError, e.what());
      keep(py::error_already_set());
    }
  }
  // Raises the kept exception, if any (GIL held).
  void rethrow() {
    if (!first_) return;
    py::error_already_set e = std::move(*first_);
    first_.reset();
    throw e;
  }

 private:
  void keep(py::error_already_set&& e) {
    if (!first_) {
      first_.emplace(std::move(e));
    } else {
      e.discard_as_unraisable("uavsim: a second exception in a callback during the same call");
    }
  }
  std::optional<py::error_already_set> first_;
};
using CallbackErrorsPtr = std::shared_ptr<CallbackErrors>;

// A Python callable held by C++ std::functions that may be copied or destroyed without the GIL: the
// reference is dropped with the GIL taken.
using PyCallable = std::shared_ptr<py::object>;
inline PyCallable hold_callable(py::object fn) {
  return PyCallable(new py::object(std::move(fn)), [](py::object* p) {
    py::gil_scoped_acquire gil;
    delete p;
  });
}

// Runs fn (which waits) without the GIL, then raises what a callback raised meanwhile, and returns
// fn's value. fn must neither touch Python objects nor raise: what it needs that can fail (a closed
// object's ConnectionError) is taken before, with the GIL, e.g. as an init-capture [&v = pv.v()].
template <class F>
auto blocking(CallbackErrors& errors, F&& fn) {
  if constexpr (std::is_void_v<decltype(fn())>) {
    {
      py::gil_scoped_release nogil;
      fn();
    }
    errors.rethrow();
  } else {
    auto r = [&] {
      py::gil_scoped_release nogil;
      return fn();
    }();
    errors.rethrow();
    return r;
  }
}

// The same for a call that answers a Result: its failure is raised after a callback's exception.
template <class F>
auto blocking_result(CallbackErrors& errors, F&& fn) {
  return unwrap(blocking(errors, std::forward<F>(fn)));
}

}  // namespace uavsim::python
