#include "uavsim/client/camera.hpp"

#include <cstdlib>
#include <cstring>
#include <utility>

#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "loop_services.hpp"
#include "sim_channel.hpp"
#include "uavsim/media/media_io.hpp"

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
  // Where the frames come from: the lockstep loop's simulator connection, or (host clock) one of
  // this subscriber's own. Either way they arrive as `frame` messages routed to deliver().
  SimChannel* channel = nullptr;
  std::unique_ptr<SimChannel> own_channel;
  int width = 0, height = 0;
  double fps = 0.0;
  CameraIntrinsics intrinsics;
  std::uint64_t received = 0;
  std::int64_t dropped = 0;
  double near_m = 0.0, far_m = 0.0;
  std::vector<std::string> classes;
  std::vector<SegmentationObject> objects;
  CameraFrame assembling;  // the capture whose parts are arriving (they come together, in order)

  Impl(EventLoop& l, CameraConfig c) : loop(l), config(std::move(c)) {}

  // one part of a capture (docs/protocol.md: a header and its bytes per image, parts 0 .. parts-1)
  void deliver(const Json& h, std::string_view bytes) {
    const int part = h.value("part", 0);
    const int parts = h.value("parts", 1);
    if (part == 0) assembling = header_of(h);
    CameraFrame& f = assembling;
    const int w = h.value("width", 0), ht = h.value("height", 0);
    const std::string format = h.value("format", std::string("rgb"));
    const std::size_t pixels = static_cast<std::size_t>(w) * static_cast<std::size_t>(ht);
    if (format == "depth" && bytes.size() == pixels * 4) {
      f.depth_m = cv::Mat(ht, w, CV_32FC1);
      std::memcpy(f.depth_m.data, bytes.data(), bytes.size());
    } else if (format == "segmentation" && bytes.size() == pixels * 4) {
      // per pixel: uint16 object id, uint16 class id, little-endian
      const cv::Mat both(ht, w, CV_16UC2, const_cast<char*>(bytes.data()));
      cv::Mat split[2];
      cv::split(both, split);
      f.object_ids = split[0];
      f.class_ids = split[1];
    } else if (format == "jpeg") {
      const cv::Mat raw(1, static_cast<int>(bytes.size()), CV_8UC1, const_cast<char*>(bytes.data()));
      f.image = media::decode_image(raw, cv::IMREAD_COLOR);
    } else if (format == "grey" && bytes.size() == pixels) {
      f.image = cv::Mat(ht, w, CV_8UC1, const_cast<char*>(bytes.data())).clone();
    } else if (format == "rgb" && bytes.size() == pixels * 3) {
      const cv::Mat rgb(ht, w, CV_8UC3, const_cast<char*>(bytes.data()));
      cv::cvtColor(rgb, f.image, cv::COLOR_RGB2BGR);
    }
    if (part + 1 < parts) return;
    ++received;
    dropped = f.dropped;
    if (on_frame) on_frame(f);
    assembling = CameraFrame();
  }

  // what every part of a capture says alike: stamps, seq, intrinsics, pose
  CameraFrame header_of(const Json& h) const {
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
    return f;
  }

  Json request() const {
    Json r = {{"op", "camera_subscribe"}, {"camera", config.camera}};
    if (config.depth || config.segmentation) {
      Json modalities = Json::array();
      if (config.colour) modalities.push_back(wire_format(config.format));
      if (config.depth) modalities.push_back("depth");
      if (config.segmentation) modalities.push_back("segmentation");
      r["modalities"] = modalities;
    } else {
      r["format"] = wire_format(config.format);
    }
    if (config.fps > 0) r["fps"] = config.fps;
    if (config.colour && config.format == CameraFormat::kJpeg) r["quality"] = config.jpeg_quality;
    return r;
  }

  // the subscribe reply's depth range and segmentation tables
  void take_tables(const Json& res) {
    const Json depth = res.value("depth", Json::object());
    near_m = depth.value("near_m", 0.0);
    far_m = depth.value("far_m", 0.0);
    const Json seg = res.value("segmentation", Json::object());
    for (const Json& k : seg.value("classes", Json::array())) {
      const int id = k.value("id", -1);
      if (id < 0 || id > 0xFFFF) continue;
      if (classes.size() <= static_cast<std::size_t>(id)) classes.resize(static_cast<std::size_t>(id) + 1);
      classes[static_cast<std::size_t>(id)] = k.value("name", std::string());
    }
    for (const Json& o : seg.value("objects", Json::array())) {
      objects.push_back({o.value("id", 0), o.value("name", std::string()), o.value("class", 0)});
    }
  }

  // The simulator connection the frames come on: the lockstep loop's (every frame due at or before a
  // tick is read before that tick's timers run, none dropped), else one of our own, read as its
  // bytes arrive (the simulator drops frames a slow reader has not taken, and counts them).
  Result<void> open_channel(double timeout_s) {
    channel = LoopServices(loop).sim_channel();
    if (channel != nullptr) return {};
    std::string address = config.api_address;
    if (address.empty()) {
      const char* env = std::getenv("UAVSIM_API");
      address = env != nullptr && *env != '\0' ? env : "127.0.0.1:5700";
    }
    auto own = SimChannel::connect(loop, address, timeout_s);
    if (!own) return Result<void>::fail(own.code(), "camera " + config.camera + ": " + own.message());
    own_channel = std::move(*own);
    channel = own_channel.get();
    return {};
  }
};

CameraSubscriber::CameraSubscriber(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}

CameraSubscriber::~CameraSubscriber() {
  Impl& s = *impl_;
  s.channel->remove_frame_sink(s.config.camera);
  (void)s.channel->request({{"op", "camera_unsubscribe"}, {"camera", s.config.camera}}, [](const Json&) {});
}

Result<std::unique_ptr<CameraSubscriber>> CameraSubscriber::subscribe(EventLoop& loop, const CameraConfig& config,
                                                                      std::function<void(const CameraFrame&)> on_frame,
                                                                      double timeout_s) {
  using R = Result<std::unique_ptr<CameraSubscriber>>;
  loop.assert_in_loop_thread();
  if (config.camera.empty()) return R::fail(Error::kInvalidArgument, "camera: no camera name");
  if (!config.colour && !config.depth && !config.segmentation) {
    return R::fail(Error::kInvalidArgument, "camera " + config.camera + ": no image asked for (colour, depth, segmentation)");
  }
  auto impl = std::make_unique<Impl>(loop, config);
  impl->on_frame = std::move(on_frame);
  Impl* s = impl.get();
  if (auto c = s->open_channel(timeout_s); !c) return R(c.error());
  // the sink before the request: the first frame may follow the reply at once
  if (!s->channel->add_frame_sink(config.camera, [s](const Json& h, std::string_view bytes) { s->deliver(h, bytes); })) {
    return R::fail(Error::kInvalidArgument, "camera " + config.camera + ": already subscribed on this loop");
  }
  auto reply = call_and_wait(loop, *s->channel, s->request(), timeout_s, "camera " + config.camera);
  if (!reply || reply->value("ok", false) != true) {
    s->channel->remove_frame_sink(config.camera);
    if (!reply) return R(reply.error());
    return R::fail(Error::kDenied, "camera " + config.camera + ": " + reply_error_text(*reply));
  }
  const Json res = reply->value("result", Json::object());
  s->width = res.value("width", 0);
  s->height = res.value("height", 0);
  s->fps = res.value("fps", 0.0);
  s->intrinsics = intrinsics_of(res.value("intrinsics", Json()));
  s->take_tables(res);
  return std::unique_ptr<CameraSubscriber>(new CameraSubscriber(std::move(impl)));
}

int CameraSubscriber::width() const { return impl_->width; }
int CameraSubscriber::height() const { return impl_->height; }
double CameraSubscriber::fps() const { return impl_->fps; }
CameraIntrinsics CameraSubscriber::intrinsics() const { return impl_->intrinsics; }
std::uint64_t CameraSubscriber::frames_received() const { return impl_->received; }
std::int64_t CameraSubscriber::frames_dropped() const { return impl_->dropped; }
bool CameraSubscriber::connected() const { return impl_->channel->is_open(); }
double CameraSubscriber::depth_near_m() const { return impl_->near_m; }
double CameraSubscriber::depth_far_m() const { return impl_->far_m; }
const std::vector<std::string>& CameraSubscriber::segmentation_classes() const { return impl_->classes; }
const std::vector<SegmentationObject>& CameraSubscriber::segmentation_objects() const { return impl_->objects; }

}  // namespace uavsim::client
