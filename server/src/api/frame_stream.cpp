#include "api/frame_stream.hpp"

#include <algorithm>
#include <cmath>
#include <iterator>
#include <optional>

#include "sim/checked_number.hpp"

namespace uavsim::server::api {

namespace {
constexpr int kDefaultJpegQuality = 90;
// the most frames a subscription may skip between two it gets (fps = camera fps / every)
constexpr int kMaxEvery = 1000000;
// a frame is dropped for a connection that still has more than this many frames' bytes queued unsent
constexpr size_t kMaxQueuedFrames = 2;

std::string dump(const nlohmann::json& j) { return j.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace); }
constexpr std::string_view kCameraOps[] = {"camera_list", "camera_subscribe", "camera_unsubscribe",
                                           "camera_blackout"};
}  // namespace

FrameStream::FrameStream(const sim::Simulation& sim, render::FrameService& service, LineServer& server,
                         std::function<bool(uint64_t)> is_lockstep)
    : sim_(sim), service_(service), server_(server), is_lockstep_(std::move(is_lockstep)) {}

void FrameStream::register_ops(OpTable& table) {
  for (std::string_view name : kCameraOps) {
    const std::string op(name);
    table.add({op, "camera",
               [this, op](uint64_t conn, const Json& request, OpReply* reply) {
                 if (op == "camera_blackout") {
                   blackout(request, sim_.time_s(), &reply->result, &reply->code, &reply->message);
                 } else {
                   handle(conn, op, request, &reply->result, &reply->code, &reply->message);
                 }
               },
               core_op_fields()});
  }
}

void FrameStream::register_unavailable(OpTable& table) {
  for (std::string_view name : kCameraOps) {
    table.add({std::string(name), "camera",
               [](uint64_t, const Json&, OpReply* reply) {
                 reply->fail("not_available", "this server renders no camera frames");
               },
               core_op_fields()});
  }
}

void FrameStream::before_tick(uint64_t conn, const Send& /*send*/) {
  if (has_subscriptions(conn)) service_.wait_delivered();
}

FrameStream::Json FrameStream::camera_json(int index) const {
  const render::FrameCamera& c = service_.cameras().at(static_cast<size_t>(index));
  return Json{{"name", c.name},
              {"vehicle", c.vehicle >= 0 ? Json(c.vehicle_name) : Json(nullptr)},
              {"vehicle_index", c.vehicle >= 0 ? Json(c.vehicle) : Json(nullptr)},
              {"width", c.width_px},
              {"height", c.height_px},
              {"fps", c.fps_hz},
              {"intrinsics", {{"fx", c.fx_px}, {"fy", c.fy_px}, {"cx", c.cx_px}, {"cy", c.cy_px}}},
              {"formats", {"rgb", "grey", "jpeg"}}};
}

bool FrameStream::has_subscriptions(uint64_t conn) const {
  auto it = subs_.find(conn);
  return it != subs_.end() && !it->second.empty();
}

void FrameStream::on_disconnect(uint64_t conn) {
  auto it = subs_.find(conn);
  if (it == subs_.end()) return;
  for (auto& [camera, sub] : it->second) sub->active = false;
  subs_.erase(it);
}

bool FrameStream::handle(uint64_t conn, const std::string& op, const Json& request, Json* result,
                         std::string* code, std::string* message) {
  auto fail = [&](const char* c, std::string m) {
    *code = c;
    *message = std::move(m);
    return false;
  };
  if (op == "camera_list") {
    Json list = Json::array();
    for (size_t i = 0; i < service_.cameras().size(); ++i) list.push_back(camera_json(static_cast<int>(i)));
    *result = {{"cameras", list}};
    return true;
  }
  auto cam_it = request.find("camera");
  if (cam_it == request.end()) return fail("missing_field", "\"camera\" (a camera name) is required");
  if (!cam_it->is_string()) return fail("bad_field", "\"camera\" must be a camera name (a string)");
  const std::string name = cam_it->get<std::string>();
  const std::optional<int> camera = service_.find(name);
  if (!camera) {
    std::string names;
    for (const render::FrameCamera& c : service_.cameras()) names += (names.empty() ? "" : ", ") + c.name;
    return fail("bad_field", "no camera named '" + name + "' (cameras: " + (names.empty() ? "none" : names) + ")");
  }
  const render::FrameCamera& info = service_.cameras()[static_cast<size_t>(*camera)];

  if (op == "camera_unsubscribe") {
    std::shared_ptr<Sub> sub;
    auto it = subs_.find(conn);
    if (it != subs_.end()) {
      auto s = it->second.find(*camera);
      if (s != it->second.end()) {
        sub = s->second;
        it->second.erase(s);
      }
    }
    if (sub) {
      // under the delivery lock: no frame of this subscription is written after the reply
      std::lock_guard<std::mutex> lock(mutex_);
      sub->active = false;
    }
    *result = {{"camera", name},
               {"subscribed", sub != nullptr},
               {"delivered", sub ? sub->delivered.load() : 0},
               {"dropped", sub ? sub->dropped.load() : 0}};
    return true;
  }

  // camera_subscribe
  render::EncodingKey key;
  if (auto f = request.find("format"); f != request.end()) {
    const auto e = f->is_string() ? render::encoding_from_name(f->get<std::string>()) : std::nullopt;
    if (!e) return fail("bad_field", "\"format\" must be \"rgb\", \"grey\" or \"jpeg\"");
    key.encoding = *e;
  }
  if (auto q = request.find("quality"); q != request.end()) {
    if (key.encoding != render::Encoding::kJpeg) {
      return fail("bad_field", "\"quality\" applies to \"jpeg\" only");
    }
    if (!q->is_number() || q->get<double>() < 1 || q->get<double>() > 100 ||
        std::floor(q->get<double>()) != q->get<double>()) {
      return fail("bad_field", "\"quality\" must be an integer in [1, 100]");
    }
    key.quality = static_cast<int>(q->get<double>());
  } else if (key.encoding == render::Encoding::kJpeg) {
    key.quality = kDefaultJpegQuality;
  }
  int every = 1;
  if (auto f = request.find("fps"); f != request.end()) {
    const double fps = f->is_number() ? f->get<double>() : -1.0;
    const double n = fps > 0 ? std::round(info.fps_hz / fps) : 0.0;
    // every frame, every second, ... up to one frame in kMaxEvery: a tiny fps (1e-300) once became
    // a divisor past INT_MAX, and its cast to int was undefined
    const std::optional<int> whole = sim::checked_integer<int>(n, 1, kMaxEvery);
    if (!(fps > 0) || !std::isfinite(fps) || !whole || std::abs(info.fps_hz / n - fps) > 1e-6 * fps) {
      return fail("bad_field", "\"fps\" must be camera '" + name + "''s fps (" + dump(Json(info.fps_hz)) +
                                   ") divided by a whole number up to " + std::to_string(kMaxEvery));
    }
    every = *whole;
  }
  auto& mine = subs_[conn];
  std::shared_ptr<Sub> sub = std::make_shared<Sub>();
  if (auto old = mine.find(*camera); old != mine.end()) {
    std::lock_guard<std::mutex> lock(mutex_);
    old->second->active = false;
    sub->next_seq = old->second->next_seq;
    sub->dropped = old->second->dropped.load();
    sub->delivered = old->second->delivered.load();
  }
  sub->conn = conn;
  sub->camera = *camera;
  sub->key = key;
  sub->every = every;
  mine[*camera] = sub;
  *result = {{"camera", name},
             {"format", render::encoding_name(key.encoding)},
             {"fps", info.fps_hz / every},
             {"quality", key.encoding == render::Encoding::kJpeg ? Json(key.quality) : Json(nullptr)},
             {"width", info.width_px},
             {"height", info.height_px},
             {"intrinsics", {{"fx", info.fx_px}, {"fy", info.fy_px}, {"cx", info.cx_px}, {"cy", info.cy_px}}},
             {"every", every}};
  return true;
}

bool FrameStream::blackout(const Json& request, double now_s, Json* result, std::string* code,
                           std::string* message) {
  auto fail = [&](const char* c, std::string m) {
    *code = c;
    *message = std::move(m);
    return false;
  };
  auto cam_it = request.find("camera");
  if (cam_it == request.end()) return fail("missing_field", "\"camera\" (a camera name) is required");
  const std::optional<int> camera =
      cam_it->is_string() ? service_.find(cam_it->get<std::string>()) : std::nullopt;
  if (!camera) return fail("bad_field", "\"camera\" must name a camera of camera_list");
  auto d = request.find("duration_s");
  if (d == request.end()) return fail("missing_field", "\"duration_s\" is required");
  // at most a day of sim time: the end stays an exact integer of microseconds
  constexpr double kMaxBlackout_s = 86400.0;
  if (!d->is_number() || !(d->get<double>() >= 0.0) || d->get<double>() > kMaxBlackout_s) {
    return fail("bad_field", "\"duration_s\" must be a number of seconds in [0, 86400]");
  }
  const int64_t from_us = std::llround(now_s * 1e6);
  const int64_t until_us = from_us + std::llround(d->get<double>() * 1e6);
  {
    std::lock_guard<std::mutex> lock(mutex_);
    blackouts_[*camera] = {from_us, until_us};
  }
  *result = {{"camera", cam_it->get<std::string>()}, {"from_s", from_us * 1e-6}, {"until_s", until_us * 1e-6}};
  return true;
}

void FrameStream::clear_blackouts() {
  std::lock_guard<std::mutex> lock(mutex_);
  blackouts_.clear();
}

void FrameStream::want(int camera, int64_t index, int64_t, std::vector<render::EncodingKey>* encodings,
                       bool* must_deliver) {
  std::vector<Pending> takers;
  for (auto& [conn, cams] : subs_) {
    auto it = cams.find(camera);
    if (it == cams.end() || index % it->second->every != 0) continue;
    Pending p;
    p.sub = it->second;
    p.seq = p.sub->next_seq++;
    p.must = is_lockstep_ && is_lockstep_(conn);
    *must_deliver = *must_deliver || p.must;
    encodings->push_back(p.sub->key);
    takers.push_back(std::move(p));
  }
  if (takers.empty()) return;
  std::lock_guard<std::mutex> lock(mutex_);
  pending_[{camera, index}] = std::move(takers);
}

void FrameStream::dropped(int camera, int64_t index) {
  std::lock_guard<std::mutex> lock(mutex_);
  auto it = pending_.find({camera, index});
  if (it == pending_.end()) return;
  for (Pending& p : it->second) {
    if (p.sub->active) ++p.sub->dropped;
  }
  pending_.erase(it);
}

void FrameStream::deliver(const render::ReadyFrame& frame) {
  std::lock_guard<std::mutex> lock(mutex_);
  auto it = pending_.find({frame.camera, frame.index});
  if (it == pending_.end()) return;
  std::vector<Pending> takers = std::move(it->second);
  pending_.erase(it);
  const render::FrameCamera& c = *frame.info;
  Json R = Json::array();
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) R.push_back(frame.R_enu_cam(i, j));
  }
  const Json pose = {{"position_enu_m",
                      {frame.position_enu_m.x(), frame.position_enu_m.y(), frame.position_enu_m.z()}},
                     {"R_enu_cam", R}};
  const Json intrinsics = {{"fx", c.fx_px}, {"fy", c.fy_px}, {"cx", c.cx_px}, {"cy", c.cy_px}};
  const auto blackout = blackouts_.find(frame.camera);
  const bool black = blackout != blackouts_.end() && frame.stamp_us >= blackout->second.first &&
                     frame.stamp_us < blackout->second.second;
  std::vector<std::pair<render::EncodingKey, std::shared_ptr<const std::string>>> black_images;
  for (Pending& p : takers) {
    Sub& sub = *p.sub;
    if (!sub.active) continue;
    const std::string* bytes = frame.image(sub.key);
    if (bytes == nullptr) continue;
    if (black) {
      // a blacked-out camera: the same frame, every pixel black (encoded once per encoding)
      auto it = std::find_if(black_images.begin(), black_images.end(),
                             [&](const auto& b) { return b.first == sub.key; });
      if (it == black_images.end()) {
        black_images.emplace_back(sub.key, render::encode_black_frame(c.width_px, c.height_px, sub.key));
        it = std::prev(black_images.end());
      }
      bytes = it->second.get();
    }
    if (!p.must && server_.pending_bytes(sub.conn) > kMaxQueuedFrames * bytes->size()) {
      ++sub.dropped;
      continue;
    }
    // what this subscription lost before this frame: frames reach a subscription in seq order, so every
    // earlier seq not delivered was dropped. (The running total `sub.dropped` may already count frames
    // after this one, which the renderer refused while this one was still being rendered.)
    const uint64_t delivered = sub.delivered.load();
    const uint64_t dropped_before = p.seq > delivered ? p.seq - delivered : 0;
    const Json header = {{"event", "frame"},
                         {"camera", c.name},
                         {"vehicle", c.vehicle >= 0 ? Json(c.vehicle_name) : Json(nullptr)},
                         {"seq", p.seq},
                         {"dropped", dropped_before},
                         {"stamp", frame.stamp_s},
                         {"stamp_us", frame.stamp_us},
                         {"width", c.width_px},
                         {"height", c.height_px},
                         {"format", render::encoding_name(sub.key.encoding)},
                         {"bytes", bytes->size()},
                         {"intrinsics", intrinsics},
                         {"pose", pose}};
    std::string message = dump(header);
    message.reserve(message.size() + 1 + bytes->size());
    message += '\n';
    message += *bytes;
    if (server_.send(sub.conn, message)) ++sub.delivered;
  }
}

}  // namespace uavsim::server::api
