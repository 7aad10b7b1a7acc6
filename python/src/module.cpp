// uavsim._core: the C++ client library (client_cpp) for Python. This unit: the module, its
// exceptions, JSON <-> Python, the event loop and the geodesy helpers.
#include <pybind11/eigen.h>
#include <pybind11/functional.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <cmath>
#include <limits>
#include <string>

#include "bindings.hpp"
#include "uavsim/client/geodesy.hpp"

namespace uavsim::python {

namespace {

// the exception classes (module-lifetime references, created once at import)
PyObject* g_uavsim_error = nullptr;
PyObject* g_invalid_argument_error = nullptr;
PyObject* g_timeout_error = nullptr;
PyObject* g_connection_error = nullptr;

PyObject* error_class(Error code) {
  switch (code) {
    case Error::kInvalidArgument:
      return g_invalid_argument_error;
    case Error::kTimeout:
      return g_timeout_error;
    case Error::kConnectionRefused:
    case Error::kNotConnected:
    case Error::kConnectionLost:
      return g_connection_error;
    default:
      return g_uavsim_error;
  }
}

PyObject* new_error_class(py::module_& m, const char* name, py::tuple bases, const char* doc) {
  const std::string qualified = std::string("uavsim._core.") + name;
  PyObject* cls = PyErr_NewExceptionWithDoc(qualified.c_str(), doc, bases.ptr(), nullptr);
  if (cls == nullptr) throw py::error_already_set();
  m.add_object(name, py::handle(cls));  // the module holds a reference; ours is the creation's
  return cls;
}

// a loop task that calls fn with the GIL, keeping what it raises for the blocking call it runs in
client::Task python_task(const PyLoop& l, py::function fn) {
  return [errors = l.errors, f = hold_callable(std::move(fn))] {
    py::gil_scoped_acquire gil;
    errors->guard([&] { (*f)(); });
  };
}

client::EventLoop& live(PyLoop& l) { return l.get(); }

std::unique_ptr<PyLoop> create_loop(const client::LoopConfig& config) {
  if (config.clock == client::LoopConfig::Clock::kLockstep) {
    checked_port(config.lockstep_port);
    if (!(config.lockstep_period_s > 0.0 && config.lockstep_period_s <= 60.0)) {
      raise_failure({Error::kInvalidArgument, "lockstep period_s must be in (0, 60] s, not " +
                                                  std::to_string(config.lockstep_period_s)});
    }
    checked_duration(config.lockstep_wall_timeout_s, "wall_timeout_s");
  }
  auto r = [&] {
    py::gil_scoped_release nogil;  // a lockstep join waits for the server
    return client::EventLoop::create(config);
  }();
  auto l = std::make_unique<PyLoop>();
  l->loop = unwrap(std::move(r));
  return l;
}

}  // namespace

client::EventLoop& PyLoop::get() {
  if (loop == nullptr) raise_failure({Error::kNotConnected, "event loop: closed"});
  return *loop;
}

void register_errors(py::module_& m) {
  const py::object runtime = py::reinterpret_borrow<py::object>(PyExc_RuntimeError);
  g_uavsim_error = new_error_class(m, "UavsimError", py::make_tuple(runtime),
                                   "A failure of the client library: .code (Error), .message, "
                                   ".mav_result (the vehicle's MAV_RESULT; -1 if "
                                   "none).");
  const py::object base = py::reinterpret_borrow<py::object>(g_uavsim_error);
  g_invalid_argument_error =
      new_error_class(m, "InvalidArgumentError", py::make_tuple(base, py::handle(PyExc_ValueError)),
                      "A bad argument (Error.INVALID_ARGUMENT).");
  g_timeout_error =
      new_error_class(m, "TimeoutError", py::make_tuple(base, py::handle(PyExc_TimeoutError)),
                      "No answer in time, on the loop's clock (Error.TIMEOUT).");
  g_connection_error =
      new_error_class(m, "ConnectionError", py::make_tuple(base, py::handle(PyExc_ConnectionError)),
                      "Nothing listens, or the link is down or was lost (Error.CONNECTION_REFUSED, "
                      "NOT_CONNECTED, CONNECTION_LOST).");
}

void raise_failure(const Failure& f) {
  PyObject* cls = error_class(f.code);
  const std::string text = std::string(client::error_name(f.code)) + ": " + f.message;
  py::object e = py::reinterpret_borrow<py::object>(cls)(text);
  e.attr("code") = py::cast(f.code);
  e.attr("message") = py::str(f.message);
  e.attr("mav_result") = py::int_(f.mav_result);
  PyErr_SetObject(cls, e.ptr());
  throw py::error_already_set();
}

double checked_duration(double v, const char* name, bool allow_infinite) {
  if (std::isnan(v) || v < 0.0 || (!allow_infinite && std::isinf(v))) {
    raise_failure({Error::kInvalidArgument,
                   std::string(name) + " must be a " + (allow_infinite ? "" : "finite ") +
                       "number of seconds >= 0, not " + std::to_string(v)});
  }
  return v;
}

int checked_port(int port) {
  if (port < 1 || port > 65535) {
    raise_failure(
        {Error::kInvalidArgument, "port must be in 1..65535, not " + std::to_string(port)});
  }
  return port;
}

py::object to_python(const nlohmann::json& j) {
  using T = nlohmann::json::value_t;
  switch (j.type()) {
    case T::null:
    case T::discarded:
      return py::none();
    case T::boolean:
      return py::bool_(j.get<bool>());
    case T::number_integer:
      return py::int_(j.get<std::int64_t>());
    case T::number_unsigned:
      return py::int_(j.get<std::uint64_t>());
    case T::number_float:
      return py::float_(j.get<double>());
    case T::string:
      return py::str(j.get_ref<const std::string&>());
    case T::binary: {
      const auto& b = j.get_binary();
      return py::bytes(reinterpret_cast<const char*>(b.data()), b.size());
    }
    case T::array: {
      py::list out(j.size());
      for (std::size_t i = 0; i < j.size(); ++i) out[i] = to_python(j[i]);
      return out;
    }
    case T::object: {
      py::dict out;
      for (const auto& [k, v] : j.items()) out[py::str(k)] = to_python(v);
      return out;
    }
  }
  return py::none();
}

nlohmann::json from_python(py::handle h) {
  if (h.is_none()) return nullptr;
  if (py::isinstance<py::bool_>(h)) return h.cast<bool>();
  if (py::isinstance<py::int_>(h)) {
    // ints beyond 64 bits are refused rather than wrapped
    try {
      return h.cast<std::int64_t>();
    } catch (const py::cast_error&) {
      try {
        return h.cast<std::uint64_t>();
      } catch (const py::cast_error&) {
        throw py::value_error("an int outside the 64-bit range cannot be sent as JSON");
      }
    }
  }
  if (py::isinstance<py::float_>(h)) return h.cast<double>();
  if (py::isinstance<py::str>(h)) return h.cast<std::string>();
  if (py::isinstance<py::dict>(h)) {
    nlohmann::json out = nlohmann::json::object();
    for (auto [k, v] : py::reinterpret_borrow<py::dict>(h)) {
      if (!py::isinstance<py::str>(k)) throw py::type_error("JSON object keys must be str");
      out[k.cast<std::string>()] = from_python(v);
    }
    return out;
  }
  if (py::isinstance<py::list>(h) || py::isinstance<py::tuple>(h)) {
    nlohmann::json out = nlohmann::json::array();
    for (auto v : py::reinterpret_borrow<py::iterable>(h)) out.push_back(from_python(v));
    return out;
  }
  // numpy scalars and arrays
  if (py::hasattr(h, "tolist") && py::hasattr(h, "dtype")) return from_python(h.attr("tolist")());
  throw py::type_error(std::string("cannot send a ") +
                       py::str(py::type::handle_of(h).attr("__name__")).cast<std::string>() +
                       " as JSON");
}

void bind_loop(py::module_& m) {
  py::enum_<Error>(m, "Error", "The client library's error codes (UavsimError.code).")
      .value("TIMEOUT", Error::kTimeout)
      .value("CONNECTION_REFUSED", Error::kConnectionRefused)
      .value("NOT_CONNECTED", Error::kNotConnected)
      .value("CONNECTION_LOST", Error::kConnectionLost)
      .value("DENIED", Error::kDenied)
      .value("FAILED", Error::kFailed)
      .value("UNSUPPORTED", Error::kUnsupported)
      .value("TEMPORARILY_REJECTED", Error::kTemporarilyRejected)
      .value("CANCELLED", Error::kCancelled)
      .value("NOT_READY", Error::kNotReady)
      .value("INVALID_ARGUMENT", Error::kInvalidArgument)
      .value("IO", Error::kIo)
      .value("PROTOCOL", Error::kProtocol);
  register_errors(m);

  py::class_<client::LoopConfig> config(
      m, "LoopConfig", "How an EventLoop keeps time: the host clock or the simulator's lockstep.");
  py::enum_<client::LoopConfig::Clock>(config, "Clock")
      .value("HOST", client::LoopConfig::Clock::kHost)
      .value("LOCKSTEP", client::LoopConfig::Clock::kLockstep);
  config.def(py::init<>())
      .def_readwrite("clock", &client::LoopConfig::clock)
      .def_readwrite("lockstep_host", &client::LoopConfig::lockstep_host)
      .def_readwrite("lockstep_port", &client::LoopConfig::lockstep_port)
      .def_readwrite("lockstep_period_s", &client::LoopConfig::lockstep_period_s)
      .def_readwrite("lockstep_wall_timeout_s", &client::LoopConfig::lockstep_wall_timeout_s)
      .def_static("from_env", &client::LoopConfig::from_env,
                  "The host clock, unless UAVSIM_LOCKSTEP=host:port[/period_s] is set.")
      .def_static("host", &client::LoopConfig::host)
      .def_static("lockstep", &client::LoopConfig::lockstep, py::arg("host"), py::arg("port"),
                  py::arg("period_s") = 0.01);

  py::class_<PyLoop>(m, "EventLoop",
                     R"(The event loop a program's vehicles, cameras and timers run on.

Its clock is the host's steady clock, or under lockstep the simulator's: now() is sim time and the
simulation waits while the program works on a tick. Every method belongs to the thread that made the loop;
post() and stop() alone may be called from another thread. Blocking calls release the GIL; callbacks run
on the loop's thread with the GIL, and an exception one raises is raised by the blocking call it ran in.)")
      .def(py::init([](const client::LoopConfig& c) { return create_loop(c); }),
           py::arg("config") = client::LoopConfig::host())
      .def_static(
          "host", [] { return create_loop(client::LoopConfig::host()); },
          "A loop on the host clock.")
      .def_static(
          "lockstep",
          [](const std::string& host, int port, double period_s, double wall_timeout_s) {
            client::LoopConfig c = client::LoopConfig::lockstep(host, port, period_s);
            c.lockstep_wall_timeout_s = wall_timeout_s;
            return create_loop(c);
          },
          py::arg("host"), py::arg("port"), py::arg("period_s") = 0.01,
          py::arg("wall_timeout_s") = 60.0,
          "Joins the simulator's lockstep at host:port with this tick period (sim seconds).")
      .def_static(
          "from_env", [] { return create_loop(client::LoopConfig::from_env()); },
          "Lockstep when UAVSIM_LOCKSTEP=host:port[/period_s] is set, else the host clock.")
      .def(
          "now", [](PyLoop& l) { return live(l).now(); },
          "Seconds on the loop's clock (sim time of the current tick under lockstep).")
      .def_property_readonly("is_lockstep", [](PyLoop& l) { return live(l).is_lockstep(); })
      .def_property_readonly("clock_alive", [](PyLoop& l) { return live(l).clock_alive(); })
      .def(
          "call_after",
          [](PyLoop& l, double delay_s, py::function fn) {
            return live(l).call_after(checked_duration(delay_s, "delay_s"),
                                      python_task(l, std::move(fn)));
          },
          py::arg("delay_s"), py::arg("fn"),
          "Runs fn() once after delay_s (loop clock); returns a timer id.")
      .def(
          "call_every",
          [](PyLoop& l, double period_s, py::function fn) {
            if (!(std::isfinite(period_s) && period_s > 0.0)) {
              raise_failure({Error::kInvalidArgument,
                             "period_s must be a finite number of seconds > 0, not " +
                                 std::to_string(period_s)});
            }
            return live(l).call_every(period_s, python_task(l, std::move(fn)));
          },
          py::arg("period_s"), py::arg("fn"),
          "Runs fn() every period_s (loop clock), first one period from now.")
      .def(
          "cancel", [](PyLoop& l, client::TimerId id) { return live(l).cancel(id); },
          py::arg("timer"))
      .def(
          "post", [](PyLoop& l, py::function fn) { live(l).post(python_task(l, std::move(fn))); },
          py::arg("fn"),
          "Thread-safe: runs fn() on the loop's thread soon (at the current tick under lockstep).")
      .def(
          "run", [](PyLoop& l) { blocking(*l.errors, [&loop = live(l)] { loop.run(); }); },
          "Dispatches until stop() is called.")
      .def(
          "stop", [](PyLoop& l) { live(l).stop(); }, "Thread-safe: ends run().")
      .def(
          "run_for",
          [](PyLoop& l, double duration_s) {
            checked_duration(duration_s, "duration_s");
            blocking_result(*l.errors, [&, &loop = live(l)] { return loop.run_for(duration_s); });
          },
          py::arg("duration_s"),
          "Dispatches for duration_s of loop time (ConnectionError if the lockstep dies).")
      .def(
          "run_until",
          [](PyLoop& l, py::function pred, double timeout_s, const std::string& what) {
            checked_duration(timeout_s, "timeout_s", true);
            CallbackErrors& errors = *l.errors;
            bool raised = false;
            const auto p = hold_callable(std::move(pred));
            blocking_result(errors, [&, &loop = live(l)] {
              return loop.run_until(
                  [&]() -> bool {
                    py::gil_scoped_acquire gil;
                    bool done = false;
                    errors.guard([&] {
                      raised = true;  // until the call returns
                      done = py::cast<bool>((*p)());
                      raised = false;
                    });
                    return done || raised;  // an exception ends the wait; blocking() raises it
                  },
                  timeout_s, what);
            });
          },
          py::arg("pred"), py::arg("timeout_s"), py::arg("what") = "condition",
          "Dispatches until pred() is true; TimeoutError after timeout_s of loop time.")
      .def(
          "run_busy",
          [](PyLoop& l, double duration_s, py::function fn) {
            checked_duration(duration_s, "duration_s");
            CallbackErrors& errors = *l.errors;
            const auto f = hold_callable(std::move(fn));
            blocking(errors, [&, &loop = live(l)] {
              loop.run_busy(duration_s, [&] {
                py::gil_scoped_acquire gil;
                errors.guard([&] { (*f)(); });
              });
            });
          },
          py::arg("duration_s"), py::arg("fn"),
          "Runs fn() as if it took duration_s of sim time without holding the simulation back "
          "(lockstep).")
      .def_property(
          "lockstep_pipelined", [](PyLoop& l) { return live(l).lockstep_pipelined(); },
          [](PyLoop& l, bool on) { live(l).set_lockstep_pipelined(on); })
      .def_property_readonly("in_loop_thread", [](PyLoop& l) { return live(l).in_loop_thread(); })
      .def(
          "close",
          [](PyLoop& l) {
            if (l.users > 0) {
              raise_failure(
                  {Error::kNotReady, "event loop: close its " + std::to_string(l.users) +
                                         " vehicle(s), camera(s), radio(s) and switches first"});
            }
            l.loop.reset();
          },
          "Destroys the loop now (a lockstep loop leaves the lockstep); later calls raise "
          "ConnectionError.")
      .def_property_readonly("closed", [](PyLoop& l) { return l.loop == nullptr; });

  // geodesy (pure functions; a local frame about an origin)
  py::class_<client::Geodetic>(m, "Geodetic")
      .def(py::init([](double lat, double lon, double alt) {
             return client::Geodetic{lat, lon, alt};
           }),
           py::arg("lat_deg") = 0.0, py::arg("lon_deg") = 0.0, py::arg("alt_m") = 0.0)
      .def_readwrite("lat_deg", &client::Geodetic::lat_deg)
      .def_readwrite("lon_deg", &client::Geodetic::lon_deg)
      .def_readwrite("alt_m", &client::Geodetic::alt_m)
      .def("__repr__", [](const client::Geodetic& g) {
        return "Geodetic(lat_deg=" + std::to_string(g.lat_deg) +
               ", lon_deg=" + std::to_string(g.lon_deg) + ", alt_m=" + std::to_string(g.alt_m) +
               ")";
      });
  py::class_<client::GeodeticOrigin>(m, "GeodeticOrigin")
      .def(py::init([](double lat, double lon, double alt, double heading) {
             return client::GeodeticOrigin{lat, lon, alt, heading};
           }),
           py::arg("lat_deg") = 0.0, py::arg("lon_deg") = 0.0, py::arg("alt_m") = 0.0,
           py::arg("heading_rad") = 0.0)
      .def_readwrite("lat_deg", &client::GeodeticOrigin::lat_deg)
      .def_readwrite("lon_deg", &client::GeodeticOrigin::lon_deg)
      .def_readwrite("alt_m", &client::GeodeticOrigin::alt_m)
      .def_readwrite("heading_rad", &client::GeodeticOrigin::heading_rad);
  m.def("ned_from_geodetic", &client::ned_from_geodetic, py::arg("origin"), py::arg("point"));
  m.def("geodetic_from_ned", &client::geodetic_from_ned, py::arg("origin"), py::arg("ned_m"));
  m.def("enu_from_geodetic", &client::enu_from_geodetic, py::arg("origin"), py::arg("point"));
  m.def("geodetic_from_enu", &client::geodetic_from_enu, py::arg("origin"), py::arg("enu_m"));
  m.def("wrap_pi", &client::wrap_pi, py::arg("a_rad"));
}

}  // namespace uavsim::python

PYBIND11_MODULE(_core, m) {
  m.doc() = "uavsim's C++ client library (client_cpp) bound for Python; use the package `uavsim`.";
  uavsim::python::bind_loop(m);
  uavsim::python::bind_sim_connection(m);
  uavsim::python::bind_vehicle(m);
  uavsim::python::bind_devices(m);
}
