#include "uavsim/client/camera.hpp"

#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "api_stream.hpp"
#include "event_loop_impl.hpp"
#include "net.hpp"

namespace uavsim::client {

namespace {
using Json = nlohmann::json;

const char* wire_format(CameraFormat f) {
  switch (f) {
    case CameraFormat::kGrey: return "grey";
    case CameraFormat::kJpeg: return "jpeg";
    default: return "rgb";
  }
}

CameraIntrinsics intrinsics_of(const Json& j) {
  CameraIntrinsics k;
  if (!j.is_object()) return k;
  k.fx = j.value("fx", 0.0);
  k.fy = j.value("fy", 0.0);
  k.cx = j.value("cx", 0.0);
  k.cy = j.value("cy", 0.0);
  return k;
}
}  // namespace

struct CameraSubscriber::Impl {
  EventLoop& loop;
  CameraConfig config;
  std::function<void(const CameraFrame&)> on_frame;
  bool lockstep = false;
  int fd = -1;  // own connection (host clock)
  ApiStream stream;
  std::optional<Json> reply;
  int width = 0, height = 0;
  double fps = 0.0;
  CameraIntrinsics intrinsics;
  std::uint64_t received = 0;
  std::int64_t dropped = 0;

  Impl(EventLoop& l, CameraConfig c) : loop(l), config(std::move(c)) {}

  void on_message(const Json& j, std::string_view bytes) {
    if (!j.is_object()) return;
    if (j.value("event", std::string()) == "frame") {
      if (j.value("camera", std::string()) == config.camera) deliver(j, bytes);
      return;
    }
    if (j.contains("ok") && j.value("id", Json()) == "cam") reply = j;
  }

  void deliver(const Json& h, std::string_view bytes) {
    CameraFrame f;
    f.camera = config.camera;
    f.vehicle = h.value("vehicle", Json()).is_string() ? h["vehicle"].get<std::string>() : "";
    f.seq = h.value("seq", std::int64_t{0});
    f.dropped = h.value("dropped", std::int64_t{0});
    f.stamp_s = h.value("stamp", 0.0);
    f.stamp_us = h.value("stamp_us", std::int64_t{0});
    f.intrinsics = intrinsics_of(h.value("intrinsics", Json()));
    const Json pose = h.value("pose", Json::object());
    if (pose.contains("position_enu_m") && pose["position_enu_m"].size() == 3) {
      for (int i = 0; i < 3; ++i) f.pose.position_enu_m[i] = pose["position_enu_m"][i].get<double>();
    }
    if (pose.contains("R_enu_cam") && pose["R_enu_cam"].size() == 9) {
      for (int i = 0; i < 9; ++i) f.pose.R_enu_cam(i / 3, i % 3) = pose["R_enu_cam"][i].get<double>();
    }
    const int w = h.value("width", 0), ht = h.value("height", 0);
    const std::string format = h.value("format", std::string("rgb"));
    if (format == "jpeg") {
      const cv::Mat raw(1, static_cast<int>(bytes.size()), CV_8UC1, const_cast<char*>(bytes.data()));
      f.image = cv::imdecode(raw, cv::IMREAD_COLOR);
    } else if (format == "grey" && bytes.size() == static_cast<std::size_t>(w) * ht) {
      f.image = cv::Mat(ht, w, CV_8UC1, const_cast<char*>(bytes.data())).clone();
    } else if (bytes.size() == static_cast<std::size_t>(w) * ht * 3) {
      const cv::Mat rgb(ht, w, CV_8UC3, const_cast<char*>(bytes.data()));
      cv::cvtColor(rgb, f.image, cv::COLOR_RGB2BGR);
    }
    ++received;
    dropped = f.dropped;
    if (on_frame) on_frame(f);
  }

  void on_io(std::uint32_t what) {
    if (!(what & EventLoop::kReadable)) return;
    char buf[65536];
    for (;;) {
      const ssize_t n = ::recv(fd, buf, sizeof(buf), MSG_DONTWAIT);
      if (n > 0) {
        stream.feed(buf, static_cast<std::size_t>(n), [this](const Json& j, std::string_view b) { on_message(j, b); });
        if (fd < 0) return;
        continue;
      }
      if (n < 0 && errno == EINTR) continue;
      if (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK)) return;
      close_fd();
      return;
    }
  }

  void close_fd() {
    if (fd < 0) return;
    loop.unwatch_fd(fd);
    ::close(fd);
    fd = -1;
  }

  Json request() const {
    Json r = {{"op", "camera_subscribe"}, {"camera", config.camera}, {"format", wire_format(config.format)}};
    if (config.fps > 0) r["fps"] = config.fps;
    if (config.format == CameraFormat::kJpeg) r["quality"] = config.jpeg_quality;
    return r;
  }
};

CameraSubscriber::CameraSubscriber(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}

CameraSubscriber::~CameraSubscriber() {
  Impl& s = *impl_;
  if (s.lockstep) {
    auto& li = s.loop.impl();
    li.frame_sinks.erase(s.config.camera);
    (void)li.api_request({{"op", "camera_unsubscribe"}, {"camera", s.config.camera}}, [](const Json&) {});
  } else {
    s.close_fd();
  }
}

Result<std::unique_ptr<CameraSubscriber>> CameraSubscriber::subscribe(EventLoop& loop, const CameraConfig& config,
                                                                      std::function<void(const CameraFrame&)> on_frame,
                                                                      double timeout_s) {
  using R = Result<std::unique_ptr<CameraSubscriber>>;
  loop.assert_in_loop_thread();
  if (config.camera.empty()) return R::fail(Error::kInvalidArgument, "camera: no camera name");
  auto impl = std::make_unique<Impl>(loop, config);
  impl->on_frame = std::move(on_frame);
  Impl* s = impl.get();
  const Json req = s->request();

  if (loop.is_lockstep()) {
    auto& li = loop.impl();
    if (li.frame_sinks.count(config.camera)) {
      return R::fail(Error::kInvalidArgument, "camera " + config.camera + ": already subscribed on this loop");
    }
    s->lockstep = true;
    if (!li.api_request(req, [s](const Json& j) { s->reply = j; })) {
      return R::fail(Error::kConnectionLost, "camera " + config.camera + ": no simulator connection");
    }
    // the sink before the reply: the first frame may follow the reply at once
    li.frame_sinks[config.camera] = [s](const Json& h, std::string_view bytes) { s->deliver(h, bytes); };
    auto w = loop.run_until([s] { return s->reply.has_value(); }, timeout_s, "camera_subscribe's reply");
    if (!w) {
      li.frame_sinks.erase(config.camera);
      return R(w.error());
    }
  } else {
    std::string address = config.api_address;
    if (address.empty()) {
      const char* env = std::getenv("UAVSIM_API");
      address = env != nullptr && *env != '\0' ? env : "127.0.0.1:5700";
    }
    std::string host;
    int port = 0;
    if (!net::parse_address(address, &host, &port)) {
      return R::fail(Error::kInvalidArgument, "camera: bad simulator API address '" + address + "'");
    }
    auto fd = net::tcp_connect(host, port, timeout_s);
    if (!fd) return R(Failure{fd.code(), "camera " + config.camera + ": simulator API: " + fd.message()});
    s->fd = *fd;
    std::string buf;
    auto hello = net::read_line(s->fd, buf, timeout_s);
    if (!hello) {
      s->close_fd();
      return R(Failure{hello.code(), "camera: no hello from the simulator API: " + hello.message()});
    }
    Json r = req;
    r["id"] = "cam";
    if (!net::send_all(s->fd, r.dump() + "\n", timeout_s)) {
      ::close(s->fd);
      return R::fail(Error::kIo, "camera: cannot send the subscription");
    }
    if (!buf.empty()) s->stream.feed(buf.data(), buf.size(), [s](const Json& j, std::string_view b) { s->on_message(j, b); });
    if (auto w = loop.watch_fd(s->fd, EventLoop::kReadable, [s](std::uint32_t what) { s->on_io(what); }); !w) {
      ::close(s->fd);
      s->fd = -1;
      return R(w.error());
    }
    auto w = loop.run_until([s] { return s->reply.has_value() || s->fd < 0; }, timeout_s, "camera_subscribe's reply");
    if (!s->reply) {
      s->close_fd();
      if (!w) return R(w.error());
      return R::fail(Error::kConnectionLost, "camera: the simulator closed the connection");
    }
  }

  const Json& rep = *s->reply;
  if (rep.value("ok", false) != true) {
    const Json e = rep.value("error", Json::object());
    if (s->lockstep) loop.impl().frame_sinks.erase(config.camera);
    s->close_fd();
    return R::fail(Error::kDenied, "camera " + config.camera + ": " + e.value("code", std::string("?")) + ": " +
                                       e.value("message", std::string("?")));
  }
  const Json res = rep.value("result", Json::object());
  s->width = res.value("width", 0);
  s->height = res.value("height", 0);
  s->fps = res.value("fps", 0.0);
  s->intrinsics = intrinsics_of(res.value("intrinsics", Json()));
  return std::unique_ptr<CameraSubscriber>(new CameraSubscriber(std::move(impl)));
}

int CameraSubscriber::width() const { return impl_->width; }
int CameraSubscriber::height() const { return impl_->height; }
double CameraSubscriber::fps() const { return impl_->fps; }
CameraIntrinsics CameraSubscriber::intrinsics() const { return impl_->intrinsics; }
std::uint64_t CameraSubscriber::frames_received() const { return impl_->received; }
std::int64_t CameraSubscriber::frames_dropped() const { return impl_->dropped; }
bool CameraSubscriber::connected() const { return impl_->lockstep ? impl_->loop.clock_alive() : impl_->fd >= 0; }

}  // namespace uavsim::client
