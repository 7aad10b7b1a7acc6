// uavsim._core: the devices on a loop: Camera (frames as numpy arrays: colour, depth,
// segmentation), Radio (air-to-air frames) and Switches (landing-pad microswitches); and _testing,
// the C++ side of the binding's own tests.
#include <pybind11/eigen.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <cstring>
#include <deque>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "bindings.hpp"
#include "uavsim/client/radio.hpp"
#include "uavsim/client/switches.hpp"

namespace uavsim::python {

namespace {

// an object shared by C++ callbacks that holds Python objects: destroyed with the GIL taken
template <class T>
std::shared_ptr<T> make_gil_shared() {
  return std::shared_ptr<T>(new T(), [](T* p) {
    py::gil_scoped_acquire gil;
    delete p;
  });
}

#ifdef UAVSIM_CLIENT_HAS_CAMERA
using client::CameraFormat;
using client::CameraFrame;
using client::CameraSubscriber;

// The Python Frame: the images of one capture as numpy arrays over the frame's own buffers, and
// what describes them. A plane the subscription did not ask for is None.
struct PyFrame {
  std::string camera;
  std::string vehicle;
  std::int64_t seq = 0;
  std::int64_t dropped = 0;
  double stamp_s = 0.0;
  std::int64_t stamp_us = 0;
  py::object image;       // uint8 H x W x 3 (BGR) or H x W (grey)
  py::object depth_m;     // float32 H x W, metres along the optical axis, NaN: nothing measured
  py::object object_ids;  // uint16 H x W, index into Camera.segmentation_objects, 0: nothing hit
  py::object class_ids;   // uint16 H x W, index into Camera.segmentation_classes, 0: nothing hit
  client::CameraIntrinsics intrinsics;
  client::CameraPose pose;
};

py::dtype dtype_of(int depth) {
  switch (depth) {
    case CV_8U:
      return py::dtype::of<std::uint8_t>();
    case CV_16U:
      return py::dtype::of<std::uint16_t>();
    case CV_32F:
      return py::dtype::of<float>();
    case CV_64F:
      return py::dtype::of<double>();
    default:
      throw py::type_error("uavsim: a frame of an unsupported pixel type (OpenCV depth " +
                           std::to_string(depth) + ")");
  }
}

// A numpy array over m's pixels without copying them: the array's base owns a cv::Mat header that
// shares m's reference-counted buffer (each frame's image is a buffer of its own: nothing writes it
// afterwards). Rows x cols (x channels when more than one), with m's own row stride.
py::array array_over(const cv::Mat& m) {
  if (m.empty()) return py::array(py::dtype::of<std::uint8_t>(), std::vector<py::ssize_t>{0, 0});
  auto* keep = new cv::Mat(m);
  py::capsule owner(keep, [](void* p) { delete static_cast<cv::Mat*>(p); });
  const auto elem = static_cast<py::ssize_t>(keep->elemSize1());
  std::vector<py::ssize_t> shape{keep->rows, keep->cols};
  std::vector<py::ssize_t> strides{static_cast<py::ssize_t>(keep->step[0]),
                                   static_cast<py::ssize_t>(keep->elemSize())};
  if (keep->channels() > 1) {
    shape.push_back(keep->channels());
    strides.push_back(elem);
  }
  return py::array(dtype_of(keep->depth()), shape, strides, keep->data, owner);
}

// a plane of the frame as an array, None when the frame has none
py::object plane_or_none(const cv::Mat& m) {
  if (m.empty()) return py::none();
  return array_over(m);
}

// The modalities asked for from Python ("rgb", "grey", "jpeg", "depth", "segmentation"; the
// protocol's names) => the subscriber's config: at most one colour format (a frame has one image),
// each name once. InvalidArgumentError naming the offending entry and the names there are.
void apply_modalities(const std::vector<std::string>& names, client::CameraConfig* c) {
  const std::string known = "rgb, grey, jpeg, depth, segmentation";
  if (names.empty() || names.size() > 5) {
    raise_failure({client::Error::kInvalidArgument, "camera: modalities must name 1-5 of " + known +
                                                        ", not " + std::to_string(names.size())});
  }
  std::optional<std::string> colour;  // the colour format's name
  bool depth = false;
  bool segmentation = false;
  for (const std::string& n : names) {
    bool repeated = false;
    if (n == "rgb" || n == "grey" || n == "jpeg") {
      if (colour && *colour != n) {
        raise_failure({client::Error::kInvalidArgument,
                       "camera: modalities may hold one of rgb, grey, jpeg (a frame has one colour "
                       "image), not both '" +
                           *colour + "' and '" + n + "'"});
      }
      repeated = colour.has_value();
      colour = n;
    } else if (n == "depth") {
      repeated = std::exchange(depth, true);
    } else if (n == "segmentation") {
      repeated = std::exchange(segmentation, true);
    } else {
      raise_failure({client::Error::kInvalidArgument,
                     "camera: unknown modality '" + n + "' (known: " + known + ")"});
    }
    if (repeated) {
      raise_failure({client::Error::kInvalidArgument,
                     "camera: modality '" + n + "' named twice in modalities"});
    }
  }
  c->colour = colour.has_value();
  if (colour) {
    c->format = *colour == "rgb"    ? CameraFormat::kBgr
                : *colour == "grey" ? CameraFormat::kGrey
                                    : CameraFormat::kJpeg;
  }
  c->depth = depth;
  c->segmentation = segmentation;
}

// what a Camera keeps for Python: the latest frame, a bounded queue of recent ones and the user's
// callback
struct CameraState {
  py::object latest = py::none();
  std::deque<py::object> queue;
  std::size_t max_queue = 0;
  std::uint64_t overflowed = 0;
  PyCallable on_frame;
};

struct PyCamera : OnLoop<CameraSubscriber> {
  PyCamera() : OnLoop("camera") {}
  std::shared_ptr<CameraState> state;
};
#endif

struct PyRadio : OnLoop<client::A2aRadio> {
  PyRadio() : OnLoop("radio") {}
};

struct PySwitches : OnLoop<client::PadSwitches> {
  PySwitches() : OnLoop("switches") {}
};

// bytes-like (bytes, bytearray, memoryview, a uint8 numpy array) -> the frame's bytes
std::vector<std::uint8_t> bytes_of(const py::buffer& b) {
  const py::buffer_info info = b.request();
  if (info.itemsize != 1) throw py::type_error("radio: data must be bytes-like with 1-byte items");
  const auto* p = static_cast<const std::uint8_t*>(info.ptr);
  if (info.ndim > 1) throw py::type_error("radio: data must be one-dimensional");
  if (info.ndim == 1 && info.strides[0] != 1)
    throw py::type_error("radio: data must be contiguous");
  return std::vector<std::uint8_t>(p, p + info.size);
}

}  // namespace

#ifdef UAVSIM_CLIENT_HAS_CAMERA
py::object frame_to_python(const CameraFrame& f) {
  PyFrame p;
  p.camera = f.camera;
  p.vehicle = f.vehicle;
  p.seq = f.seq;
  p.dropped = f.dropped;
  p.stamp_s = f.stamp_s;
  p.stamp_us = f.stamp_us;
  p.image = plane_or_none(f.image);
  p.depth_m = plane_or_none(f.depth_m);
  p.object_ids = plane_or_none(f.object_ids);
  p.class_ids = plane_or_none(f.class_ids);
  p.intrinsics = f.intrinsics;
  p.pose = f.pose;
  return py::cast(std::move(p));
}
#endif

#ifdef UAVSIM_CLIENT_HAS_CAMERA
namespace {

// a cv::Mat's pixels row by row, as C++ code reading it sees them
py::bytes mat_bytes(const cv::Mat& m) {
  std::string bytes;
  const std::size_t row = m.cols * m.elemSize();
  for (int y = 0; y < m.rows; ++y) bytes.append(reinterpret_cast<const char*>(m.ptr(y)), row);
  return py::bytes(bytes);
}

// count frames from the C++ subscriber alone, each as ({plane: its bytes as C++ sees them}, the
// Frame the binding makes of it)
std::vector<std::pair<py::dict, py::object>> capture_with_references(PyLoop& loop,
                                                                     const client::CameraConfig& c,
                                                                     int count, double timeout_s) {
  if (count < 1 || count > 1000)
    raise_failure({client::Error::kInvalidArgument, "count must be in 1..1000"});
  checked_duration(timeout_s, "timeout_s");
  auto out = make_gil_shared<std::vector<std::pair<py::dict, py::object>>>();
  auto on_frame = [out](const CameraFrame& f) {
    py::gil_scoped_acquire gil;
    py::dict refs;
    const std::pair<const char*, const cv::Mat*> planes[] = {{"image", &f.image},
                                                             {"depth_m", &f.depth_m},
                                                             {"object_ids", &f.object_ids},
                                                             {"class_ids", &f.class_ids}};
    for (const auto& [name, mat] : planes)
      if (!mat->empty()) refs[name] = mat_bytes(*mat);
    out->emplace_back(refs, frame_to_python(f));
  };
  client::EventLoop& l = loop.get();
  auto sub = blocking_result(
      *loop.errors, [&] { return CameraSubscriber::subscribe(l, c, on_frame, timeout_s); });
  blocking_result(*loop.errors, [&] {
    return l.run_until([&] { return out->size() >= static_cast<std::size_t>(count); }, timeout_s,
                       "frames of " + c.camera);
  });
  {
    py::gil_scoped_release nogil;
    sub.reset();
  }
  return std::move(*out);
}

}  // namespace
#endif

void bind_devices(py::module_& m) {
#ifdef UAVSIM_CLIENT_HAS_CAMERA
  py::enum_<CameraFormat>(m, "CameraFormat")
      .value("BGR", CameraFormat::kBgr)
      .value("GREY", CameraFormat::kGrey)
      .value("JPEG", CameraFormat::kJpeg);
  py::class_<client::CameraIntrinsics>(
      m, "CameraIntrinsics", "Pinhole intrinsics (OpenCV convention, no distortion), pixels.")
      .def_readonly("fx", &client::CameraIntrinsics::fx)
      .def_readonly("fy", &client::CameraIntrinsics::fy)
      .def_readonly("cx", &client::CameraIntrinsics::cx)
      .def_readonly("cy", &client::CameraIntrinsics::cy)
      .def(
          "matrix",
          [](const client::CameraIntrinsics& k) {
            Eigen::Matrix3d K;
            K << k.fx, 0.0, k.cx, 0.0, k.fy, k.cy, 0.0, 0.0, 1.0;
            return K;
          },
          "The 3x3 camera matrix K.");
  py::class_<client::CameraPose>(m, "CameraPose",
                                 "Where the camera was: optical centre and camera -> ENU rotation.")
      .def_readonly("position_enu_m", &client::CameraPose::position_enu_m)
      .def_readonly("R_enu_cam", &client::CameraPose::R_enu_cam);
  py::class_<client::SegmentationObject>(
      m, "SegmentationObject",
      "An object of the segmentation images: its id (in Frame.object_ids), name and class id.")
      .def_readonly("id", &client::SegmentationObject::id)
      .def_readonly("name", &client::SegmentationObject::name)
      .def_readonly("class_id", &client::SegmentationObject::class_id)
      .def("__repr__", [](const client::SegmentationObject& o) {
        return "<SegmentationObject " + std::to_string(o.id) + " " + o.name + " class " +
               std::to_string(o.class_id) + ">";
      });
  py::class_<PyFrame>(m, "Frame", R"(A camera frame: the images of one capture and its sim stamp.

The images are numpy arrays over the C++ frame's own buffers (no copy), None where the
subscription did not ask for them: image (uint8, BGR H x W x 3 or grey H x W), depth_m (float32 H x W,
metres along the optical axis, NaN where nothing was measured), object_ids and class_ids (uint16 H x W,
0 where nothing was hit; names in Camera.segmentation_objects and Camera.segmentation_classes).)")
      .def_readonly("camera", &PyFrame::camera)
      .def_readonly("vehicle", &PyFrame::vehicle)
      .def_readonly("seq", &PyFrame::seq)
      .def_readonly("dropped", &PyFrame::dropped)
      .def_readonly("stamp_s", &PyFrame::stamp_s)
      .def_readonly("stamp_us", &PyFrame::stamp_us)
      .def_readonly("image", &PyFrame::image)
      .def_readonly("depth_m", &PyFrame::depth_m)
      .def_readonly("object_ids", &PyFrame::object_ids)
      .def_readonly("class_ids", &PyFrame::class_ids)
      .def_readonly("intrinsics", &PyFrame::intrinsics)
      .def_readonly("pose", &PyFrame::pose)
      .def("__repr__", [](const PyFrame& f) {
        return "<Frame " + f.camera + " seq " + std::to_string(f.seq) + " at " +
               std::to_string(f.stamp_s) + " s>";
      });

  py::class_<PyCamera>(m, "Camera", R"(A camera's frames from the simulator, as numpy arrays.

What each frame holds: one colour format (format=, default BGR), or modalities=, a list of the
protocol's names "rgb", "grey", "jpeg" (at most one of these three), "depth", "segmentation", where the
camera gives them (the world's or --camera's modalities=); all images of a frame show one instant.

Under a lockstep loop every frame due at or before a tick is delivered before that tick's timers run;
on the host clock frames come as they arrive (a slow reader loses some, counted in frames_dropped).
Each frame goes to on_frame(Frame) if given, becomes `latest`, and is queued for take_frames() (the
oldest dropped past `queue` frames).)")
      .def_static(
          "subscribe",
          [](PyLoop& loop, const std::string& camera, std::optional<CameraFormat> format,
             std::optional<std::vector<std::string>> modalities, double fps, int jpeg_quality,
             const std::string& api_address, std::optional<py::function> on_frame, int queue,
             double timeout_s) {
            if (!(std::isfinite(fps) && fps >= 0.0))
              raise_failure({client::Error::kInvalidArgument, "fps must be >= 0"});
            if (jpeg_quality < 1 || jpeg_quality > 100) {
              raise_failure({client::Error::kInvalidArgument, "jpeg_quality must be in 1..100"});
            }
            if (queue < 0 || queue > 4096)
              raise_failure({client::Error::kInvalidArgument, "queue must be in 0..4096"});
            checked_duration(timeout_s, "timeout_s");
            if (format && modalities) {
              raise_failure(
                  {client::Error::kInvalidArgument, "camera: give format or modalities, not both"});
            }
            client::CameraConfig c;
            c.camera = camera;
            if (format) c.format = *format;
            if (modalities) apply_modalities(*modalities, &c);
            c.fps = fps;
            c.jpeg_quality = jpeg_quality;
            c.api_address = api_address;
            auto pc = std::make_unique<PyCamera>();
            pc->state = make_gil_shared<CameraState>();
            pc->state->max_queue = static_cast<std::size_t>(queue);
            if (on_frame) pc->state->on_frame = hold_callable(std::move(*on_frame));
            auto deliver = [errors = loop.errors, st = pc->state](const CameraFrame& f) {
              py::gil_scoped_acquire gil;
              errors->guard([&] {
                py::object frame = frame_to_python(f);
                st->latest = frame;
                if (st->max_queue > 0) {
                  if (st->queue.size() >= st->max_queue) {
                    st->queue.pop_front();
                    ++st->overflowed;
                  }
                  st->queue.push_back(frame);
                }
                if (st->on_frame) (*st->on_frame)(frame);
              });
            };
            client::EventLoop& l = loop.get();
            pc->hold(loop, blocking_result(*loop.errors, [&] {
                       return CameraSubscriber::subscribe(l, c, deliver, timeout_s);
                     }));
            return pc;
          },
          py::arg("loop"), py::arg("camera"), py::kw_only(), py::arg("format") = py::none(),
          py::arg("modalities") = py::none(), py::arg("fps") = 0.0, py::arg("jpeg_quality") = 90,
          py::arg("api_address") = "", py::arg("on_frame") = py::none(), py::arg("queue") = 16,
          py::arg("timeout_s") = 10.0, py::keep_alive<0, 1>(),
          "Subscribes to a camera (its name in the world) and waits for the simulator's answer.")
      .def_property_readonly("width", [](PyCamera& c) { return c.get().width(); })
      .def_property_readonly("height", [](PyCamera& c) { return c.get().height(); })
      .def_property_readonly("fps", [](PyCamera& c) { return c.get().fps(); })
      .def_property_readonly("intrinsics", [](PyCamera& c) { return c.get().intrinsics(); })
      .def_property_readonly(
          "depth_near_m", [](PyCamera& c) { return c.get().depth_near_m(); },
          "The depth images' near clip plane, metres (0 without depth): nothing nearer is seen.")
      .def_property_readonly(
          "depth_far_m", [](PyCamera& c) { return c.get().depth_far_m(); },
          "The depth images' far clip plane, metres (0 without depth): nothing farther is seen.")
      .def_property_readonly(
          "segmentation_classes", [](PyCamera& c) { return c.get().segmentation_classes(); },
          "The class names by class id (list index = id; 0 \"none\"); empty without segmentation.")
      .def_property_readonly(
          "segmentation_objects", [](PyCamera& c) { return c.get().segmentation_objects(); },
          "The objects by object id (list index = id; 0 \"none\"): SegmentationObjects with name "
          "and class id; the same ids in every frame and run of a world. Empty without "
          "segmentation.")
      .def_property_readonly("frames_received",
                             [](PyCamera& c) { return c.get().frames_received(); })
      .def_property_readonly("frames_dropped", [](PyCamera& c) { return c.get().frames_dropped(); })
      .def_property_readonly(
          "frames_overflowed", [](PyCamera& c) { return c.state->overflowed; },
          "Frames dropped from the take_frames() queue because it was full.")
      .def_property_readonly("connected",
                             [](PyCamera& c) { return c.obj != nullptr && c.obj->connected(); })
      .def_property_readonly(
          "latest", [](PyCamera& c) { return c.state->latest; },
          "The last frame (None before one).")
      .def(
          "take_frames",
          [](PyCamera& c) {
            py::list out;
            for (auto& f : c.state->queue) out.append(f);
            c.state->queue.clear();
            return out;
          },
          "The queued frames, oldest first (the queue is emptied).")
      .def(
          "close", [](PyCamera& c) { c.close(); },
          "Unsubscribes (later calls raise ConnectionError).");
#endif

  py::class_<client::RadioCounters>(m, "RadioCounters")
      .def_readonly("sent", &client::RadioCounters::sent)
      .def_readonly("refused", &client::RadioCounters::refused)
      .def_readonly("received", &client::RadioCounters::received);
  py::class_<client::RadioFrame>(m, "RadioFrame", "A received radio frame.")
      .def_readonly("time_s", &client::RadioFrame::time_s, "Arrival, sim time.")
      .def_readonly("sender", &client::RadioFrame::from, "The sender's vehicle index.")
      .def_readonly("broadcast", &client::RadioFrame::broadcast)
      .def_property_readonly("data", [](const client::RadioFrame& f) {
        return py::bytes(reinterpret_cast<const char*>(f.data.data()), f.data.size());
      });
  m.attr("RADIO_MAX_FRAME_BYTES") = client::kRadioMaxFrameBytes;
  py::class_<PyRadio>(
      m, "Radio",
      R"(A vehicle's air-to-air radio: frames of 1 to max_frame_bytes bytes (the simulator's channel
says: 127 on its simple backend, 116 on ns3's 802.15.4, 1500 on ns3's 802.11). Needs a lockstep loop.)")
      .def_static(
          "open",
          [](PyLoop& loop, int vehicle, double timeout_s) {
            checked_duration(timeout_s, "timeout_s");
            auto pr = std::make_unique<PyRadio>();
            client::EventLoop& l = loop.get();
            pr->hold(loop, blocking_result(*loop.errors, [&] {
                       return client::A2aRadio::open(l, vehicle, timeout_s);
                     }));
            return pr;
          },
          py::arg("loop"), py::arg("vehicle"), py::arg("timeout_s") = 10.0, py::keep_alive<0, 1>(),
          "Opens the radio of the vehicle with this index and waits for the simulator's answer.")
      .def_property_readonly("vehicle", [](PyRadio& r) { return r.get().vehicle(); })
      .def_property_readonly(
          "max_frame_bytes", [](PyRadio& r) { return r.get().max_frame_bytes(); },
          "The largest frame the simulator's radio channel carries, bytes.")
      .def(
          "send",
          [](PyRadio& r, const py::buffer& data, int to) {
            unwrap(r.get().send(bytes_of(data), to));
          },
          py::arg("data"), py::arg("to") = -1,
          "Puts a frame on air: to every vehicle in range (to < 0) or to one.")
      .def(
          "take_received", [](PyRadio& r) { return r.get().take_received(); },
          "The frames received since the last call, in order of arrival.")
      .def_property_readonly("counters", [](PyRadio& r) { return r.get().counters(); })
      .def(
          "close", [](PyRadio& r) { r.close(); },
          "Closes the radio (later calls raise ConnectionError).");

  py::class_<client::SwitchState>(m, "SwitchState")
      .def_readonly("time_s", &client::SwitchState::time_s)
      .def_readonly("closed", &client::SwitchState::closed)
      .def("any", &client::SwitchState::any);
  py::class_<PySwitches>(m, "Switches",
                         "A vehicle's landing-pad microswitches. Needs a lockstep loop.")
      .def_static(
          "subscribe",
          [](PyLoop& loop, const std::string& vehicle, std::optional<py::function> on_change,
             double timeout_s) {
            checked_duration(timeout_s, "timeout_s");
            auto ps = std::make_unique<PySwitches>();
            std::function<void(const client::SwitchState&)> cb;
            if (on_change) {
              cb = [errors = loop.errors,
                    f = hold_callable(std::move(*on_change))](const client::SwitchState& s) {
                py::gil_scoped_acquire gil;
                errors->guard([&] { (*f)(s); });
              };
            }
            client::EventLoop& l = loop.get();
            ps->hold(loop, blocking_result(*loop.errors, [&] {
                       return client::PadSwitches::subscribe(l, vehicle, cb, timeout_s);
                     }));
            return ps;
          },
          py::arg("loop"), py::arg("vehicle"), py::arg("on_change") = py::none(),
          py::arg("timeout_s") = 10.0, py::keep_alive<0, 1>(),
          "Subscribes to the switches of a vehicle (its name, e.g. \"uav0\").")
      .def_property_readonly(
          "state", [](PySwitches& s) { return s.get().state(); }, "The last state received.")
      .def(
          "close", [](PySwitches& s) { s.close(); },
          "Unsubscribes (later calls raise ConnectionError).");

#ifdef UAVSIM_CLIENT_HAS_CAMERA
  // the binding's own tests: frames taken with the C++ subscriber alone, each with byte copies of
  // its cv::Mats made in C++ beside the Frame the binding makes of it (tests/python compares the
  // two)
  py::module_ testing = m.def_submodule("_testing", "C++ helpers for the binding's tests.");
  testing.def(
      "capture_frames",
      [](PyLoop& loop, const std::string& camera, int count, CameraFormat format,
         double timeout_s) {
        client::CameraConfig c;
        c.camera = camera;
        c.format = format;
        py::list frames;
        for (auto& [refs, frame] : capture_with_references(loop, c, count, timeout_s))
          frames.append(py::make_tuple(refs["image"], frame));
        return frames;
      },
      py::arg("loop"), py::arg("camera"), py::arg("count"), py::arg("format") = CameraFormat::kBgr,
      py::arg("timeout_s") = 30.0);
  testing.def(
      "capture_planes",
      [](PyLoop& loop, const std::string& camera, int count,
         const std::vector<std::string>& modalities, double timeout_s) {
        client::CameraConfig c;
        c.camera = camera;
        apply_modalities(modalities, &c);
        py::list frames;
        for (auto& [refs, frame] : capture_with_references(loop, c, count, timeout_s))
          frames.append(py::make_tuple(refs, frame));
        return frames;
      },
      py::arg("loop"), py::arg("camera"), py::arg("count"), py::arg("modalities"),
      py::arg("timeout_s") = 30.0,
      "[({plane: bytes}, Frame)]: each frame's planes (image, depth_m, object_ids, class_ids) "
      "as C++ reads them, row by row, beside the Frame.");
#endif
}

}  // namespace uavsim::python
