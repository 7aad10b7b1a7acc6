// uavsim._core: SimConnection, the blocking client of the simulator's sim API (world control,
// ground truth, events, faults, wind), with JSON as Python dicts.
#include "uavsim/client/sim_connection.hpp"

#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <cstdint>
#include <map>
#include <optional>
#include <string>

#include "bindings.hpp"

namespace uavsim::python {

namespace {

using client::SimConnection;
using client::SimMessage;

// A connection with the exceptions its message handlers raised.
struct PySim {
  std::unique_ptr<SimConnection> conn;
  CallbackErrorsPtr errors = std::make_shared<CallbackErrors>();
};

SimConnection& open(PySim& s) {
  if (s.conn == nullptr) raise_failure({Error::kNotConnected, "sim connection: closed"});
  return *s.conn;
}

// one request's reply, waited for without the GIL
py::object call(PySim& s, const std::function<Result<nlohmann::json>(SimConnection&)>& fn) {
  SimConnection& c = open(s);
  return to_python(blocking_result(*s.errors, [&] { return fn(c); }));
}

double wall_timeout(double timeout_s) { return checked_duration(timeout_s, "timeout_s"); }

}  // namespace

void bind_sim_connection(py::module_& m) {
  py::class_<SimMessage>(m, "SimMessage", "A message the server streamed: {\"event\": KIND, ...}.")
      .def_property_readonly("kind", &SimMessage::kind,
                             "The message's \"event\" field (\"tick\", \"frame\", ...).")
      .def_property_readonly(
          "json", [](const SimMessage& s) { return to_python(s.json); }, "The message as a dict.")
      .def_property_readonly(
          "payload", [](const SimMessage& s) { return py::bytes(s.payload); },
          "A frame's image bytes; empty for every other message.")
      .def("__repr__", [](const SimMessage& s) { return "<SimMessage " + s.json.dump() + ">"; });

  py::class_<PySim>(m, "SimConnection",
                    R"(A blocking client of the simulator's sim API (docs/protocol.md).

Requests send a dict with "op" and return the reply's result as a dict; a refused request raises
UavsimError with the server's code mapped to an Error (e.g. INVALID_ARGUMENT for bad_field, UNSUPPORTED for
not_available) and "code: message" as its message. Streamed messages are queued for take_messages() or
handed to the handler registered with on_message(). Waits release the GIL; wall-clock timeouts.
A connection belongs to the thread that made it.)")
      .def_static(
          "connect",
          [](const std::string& host, int port, double timeout_s) {
            checked_port(port);
            wall_timeout(timeout_s);
            auto r = [&] {
              py::gil_scoped_release nogil;
              return SimConnection::connect(host, static_cast<std::uint16_t>(port), timeout_s);
            }();
            auto s = std::make_unique<PySim>();
            s->conn = unwrap(std::move(r));
            return s;
          },
          py::arg("host"), py::arg("port"), py::arg("timeout_s") = 10.0,
          "Connects to the sim API at host:port and reads the server's hello.")
      .def_property_readonly("hello", [](PySim& s) { return to_python(open(s).hello()); })
      .def_property_readonly("connected",
                             [](PySim& s) { return s.conn != nullptr && s.conn->connected(); })
      .def(
          "close", [](PySim& s) { s.conn.reset(); },
          "Closes the connection (later calls raise ConnectionError).")
      .def(
          "request",
          [](PySim& s, py::dict req, double timeout_s) {
            nlohmann::json j = from_python(req);
            wall_timeout(timeout_s);
            return call(s, [&](SimConnection& c) { return c.request(std::move(j), timeout_s); });
          },
          py::arg("request"), py::arg("timeout_s") = 30.0,
          "Sends a request ({\"op\": ..., fields}) and returns its reply's result.")
      .def(
          "on_message",
          [](PySim& s, const std::string& kind, std::optional<py::function> fn) {
            if (!fn) {
              open(s).on_message(kind, {});
              return;
            }
            open(s).on_message(kind, [errors = s.errors,
                                      f = hold_callable(std::move(*fn))](const SimMessage& msg) {
              py::gil_scoped_acquire gil;
              errors->guard([&] { (*f)(msg); });
            });
          },
          py::arg("kind"), py::arg("fn"),
          "Streamed messages of this kind go to fn(SimMessage) as they are read (None removes it).")
      .def(
          "take_messages", [](PySim& s) { return open(s).take_messages(); },
          "The streamed messages no handler took, oldest first (the queue is emptied).")
      .def(
          "poll",
          [](PySim& s, int timeout_ms) {
            if (timeout_ms < 0) raise_failure({Error::kInvalidArgument, "timeout_ms must be >= 0"});
            SimConnection& c = open(s);
            blocking_result(*s.errors, [&] { return c.poll(timeout_ms); });
          },
          py::arg("timeout_ms") = 0,
          "Reads and dispatches what has arrived, waiting up to timeout_ms.")
      .def("status", [](PySim& s) { return call(s, [](SimConnection& c) { return c.status(); }); })
      .def("pause", [](PySim& s) { return call(s, [](SimConnection& c) { return c.pause(); }); })
      .def("resume", [](PySim& s) { return call(s, [](SimConnection& c) { return c.resume(); }); })
      .def(
          "reset",
          [](PySim& s, std::uint64_t seed) {
            return call(s, [&](SimConnection& c) { return c.reset(seed); });
          },
          py::arg("seed"), "Back to t = 0 with this seed.")
      .def(
          "step_for",
          [](PySim& s, double sim_s, double timeout_s) {
            checked_duration(sim_s, "sim_s");
            wall_timeout(timeout_s);
            return call(s, [&](SimConnection& c) { return c.step_for(sim_s, timeout_s); });
          },
          py::arg("sim_s"), py::arg("timeout_s") = 60.0,
          "Pauses and advances the clock by sim_s seconds, returning when done.")
      .def("subscribe_events",
           [](PySim& s) { return call(s, [](SimConnection& c) { return c.subscribe_events(); }); })
      .def("truck", [](PySim& s) { return call(s, [](SimConnection& c) { return c.truck(); }); })
      .def(
          "lockstep_join",
          [](PySim& s, double period_s, double timeout_s) {
            checked_duration(period_s, "period_s");
            wall_timeout(timeout_s);
            return call(s, [&](SimConnection& c) { return c.lockstep_join(period_s, timeout_s); });
          },
          py::arg("period_s"), py::arg("timeout_s") = 10.0)
      .def("lockstep_leave",
           [](PySim& s) { return call(s, [](SimConnection& c) { return c.lockstep_leave(); }); })
      .def(
          "done",
          [](PySim& s, std::int64_t tick, const std::map<std::string, int>& mavlink_seq,
             std::optional<double> busy_until_s) {
            return call(s,
                        [&](SimConnection& c) { return c.done(tick, mavlink_seq, busy_until_s); });
          },
          py::arg("tick"), py::arg("mavlink_seq") = std::map<std::string, int>{},
          py::arg("busy_until_s") = py::none())
      .def(
          "radio_send",
          [](PySim& s, int vehicle, py::bytes data, int to) {
            const std::string bytes = data;
            return call(s, [&](SimConnection& c) { return c.radio_send(vehicle, bytes, to); });
          },
          py::arg("vehicle"), py::arg("data"), py::arg("to") = -1)
      .def(
          "radio_subscribe",
          [](PySim& s, int vehicle) {
            return call(s, [&](SimConnection& c) { return c.radio_subscribe(vehicle); });
          },
          py::arg("vehicle") = -1);
}

}  // namespace uavsim::python
