// The Python-side owners of the client library's objects, and the binding functions of each unit
// (module.cpp calls them in order: a type is registered before the signatures that name it).
#pragma once

#include <memory>
#include <string>

#include "core.hpp"
#include "uavsim/client/event_loop.hpp"

#ifdef UAVSIM_CLIENT_HAS_CAMERA
#include "uavsim/client/camera.hpp"
#endif

namespace uavsim::python {

// An EventLoop with the exceptions its Python callbacks raised. Objects made on a loop (Vehicle,
// Camera, Radio, Switches) keep its Python object alive, and hold a LoopUse while their C++ object
// lives: close() destroys the loop (leaving the lockstep) only once none does.
struct PyLoop {
  std::unique_ptr<client::EventLoop> loop;
  CallbackErrorsPtr errors = std::make_shared<CallbackErrors>();
  int users = 0;
  // the loop; ConnectionError once closed
  client::EventLoop& get();
};

// One object's use of a loop, for as long as the object's C++ side lives (declare it before that
// member, so that it is released after it).
class LoopUse {
 public:
  explicit LoopUse(PyLoop& l) : loop_(&l) { ++loop_->users; }
  ~LoopUse() { --loop_->users; }
  LoopUse(const LoopUse&) = delete;
  LoopUse& operator=(const LoopUse&) = delete;
  PyLoop& loop() const { return *loop_; }

 private:
  PyLoop* loop_;
};

// A client library object made on a loop (Vehicle, CameraSubscriber, A2aRadio, PadSwitches), as its
// Python object holds it: close() destroys it before the Python object goes, and later calls raise
// ConnectionError naming it.
template <class T>
struct OnLoop {
  explicit OnLoop(const char* what) : what_(what) {}
  PyLoop* loop = nullptr;
  std::unique_ptr<LoopUse> use;  // before obj: released after it
  std::unique_ptr<T> obj;
  // Takes obj, made on l; counts as a user of l.
  void hold(PyLoop& l, std::unique_ptr<T> o) {
    loop = &l;
    use = std::make_unique<LoopUse>(l);
    obj = std::move(o);
  }
  // The object; ConnectionError once closed. Needs the GIL.
  T& get() {
    if (obj == nullptr)
      raise_failure({client::Error::kNotConnected, std::string(what_) + ": closed"});
    return *obj;
  }
  void close() {
    obj.reset();
    use.reset();
  }

 private:
  const char* what_;
};

void bind_loop(py::module_& m);            // Error, exceptions, LoopConfig, EventLoop, geodesy
void bind_sim_connection(py::module_& m);  // SimConnection, SimMessage
void bind_vehicle(py::module_& m);         // FlightMode, Telemetry, MissionItem, Vehicle
void bind_devices(py::module_& m);         // Camera, Radio, Switches (and _testing)

#ifdef UAVSIM_CLIENT_HAS_CAMERA
// A frame as the Python Frame object: its image as a numpy array over the frame's own pixels (no
// copy: the array keeps the cv::Mat's buffer alive), stamps, intrinsics and pose. Needs the GIL.
py::object frame_to_python(const client::CameraFrame& f);
#endif

}  // namespace uavsim::python
