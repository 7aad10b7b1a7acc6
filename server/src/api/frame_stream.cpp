#include "api/frame_stream.hpp"

#include <algorithm>
#include <cmath>
#include <iterator>
#include <optional>

#include "sim/checked_number.hpp"

namespace uavsim::server::api {

std::optional<int> frame_divisor(double camera_fps_hz, double fps_hz) {
  if (!(fps_hz > 0) || !std::isfinite(fps_hz)) return std::nullopt;
  // every frame, every second, ... up to one frame in kMaxFrameDivisor: a tiny fps (1e-300) once
  // became a divisor past INT_MAX, and its cast to int was undefined
  const double n = std::round(camera_fps_hz / fps_hz);
  const std::optional<int> whole = sim::checked_integer<int>(n, 1, kMaxFrameDivisor);
  if (!whole || std::abs(camera_fps_hz / n - fps_hz) > 1e-6 * fps_hz) return std::nullopt;
  return whole;
}

namespace {
constexpr int kDefaultJpegQuality = 90;
// a frame is dropped for a connection that still has more than this many frames' bytes queued
// unsent
constexpr size_t kMaxQueuedFrames = 2;
// the most bytes one capture (every image of a subscription's frame) may have: with
// kMaxQueuedFrames more queued it stays below the line server's 64 MiB per connection, beyond which
// it closes the connection as overloaded
constexpr size_t kMaxCaptureBytes = 20u << 20;
// rgb, grey, jpeg, depth, segmentation
constexpr size_t kMaxModalities = 5;

std::string dump(const nlohmann::json& j) {
  return j.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
}
// the modalities a camera gives, as camera_list names them
nlohmann::json modality_list(const render::Modalities& m) {
  nlohmann::json list = nlohmann::json::array();
  if (m.rgb) list.push_back("rgb");
  if (m.grey) list.push_back("grey");
  if (m.depth) list.push_back("depth");
  if (m.segmentation) list.push_back("segmentation");
  return list;
}
constexpr std::string_view kCameraOps[] = {"camera_list", "camera_subscribe", "camera_unsubscribe",
                                           "camera_blackout"};
}  // namespace

FrameStream::FrameStream(const sim::Simulation& sim, render::FrameService& service,
                         LineServer& server, std::function<bool(uint64_t)> is_lockstep)
    : sim_(sim), service_(service), server_(server), is_lockstep_(std::move(is_lockstep)) {}

void FrameStream::register_ops(OpTable& table) {
  const OpRegistrar<FrameStream> add(table, this, "camera");
  add("camera_list", &FrameStream::op_list);
  add("camera_subscribe", &FrameStream::op_subscribe);
  add("camera_unsubscribe", &FrameStream::op_unsubscribe);
  add("camera_blackout", &FrameStream::op_blackout);
}

void FrameStream::register_unavailable(OpTable& table) {
  for (std::string_view name : kCameraOps) {
    table.add({std::string(name), "camera",
               [](uint64_t, const Json&, OpReply* reply) {
                 reply->fail(ApiError::kNotAvailable, "this server renders no camera frames");
               },
               core_op_fields()});
  }
}

void FrameStream::before_tick(uint64_t conn, const Send& /*send*/) {
  if (has_subscriptions(conn)) service_.wait_due();
}

FrameStream::Json FrameStream::camera_json(int index) const {
  const render::FrameCamera& c = service_.cameras().at(static_cast<size_t>(index));
  Json formats = Json::array();
  if (c.modalities.rgb) formats.push_back("rgb");
  if (c.modalities.grey) formats.push_back("grey");
  if (c.modalities.rgb) formats.push_back("jpeg");
  const Json modalities = modality_list(c.modalities);
  return Json{{"name", c.name},
              {"vehicle", c.vehicle >= 0 ? Json(c.vehicle_name) : Json(nullptr)},
              {"vehicle_index", c.vehicle >= 0 ? Json(c.vehicle) : Json(nullptr)},
              {"width", c.width_px},
              {"height", c.height_px},
              {"fps", c.fps_hz},
              {"intrinsics", {{"fx", c.fx_px}, {"fy", c.fy_px}, {"cx", c.cx_px}, {"cy", c.cy_px}}},
              {"formats", formats},
              {"modalities", modalities}};
}

FrameStream::Json FrameStream::depth_json(const render::FrameCamera& c) const {
  return Json{{"near_m", c.depth_near_m},
              {"far_m", c.depth_far_m},
              {"invalid", "nan"},
              {"noise_m", c.depth_noise_m},
              {"dropout", c.depth_dropout},
              {"max_m", c.depth_max_m ? Json(*c.depth_max_m) : Json(nullptr)}};
}

FrameStream::Json FrameStream::segmentation_json() const {
  Json classes = Json::array();
  for (int k = 0; k < render::kSegmentClassCount; ++k) {
    classes.push_back(
        {{"id", k}, {"name", render::segment_class_name(static_cast<render::SegmentClass>(k))}});
  }
  Json objects = Json::array();
  for (const render::SegmentObject& o : service_.labels().objects) {
    objects.push_back({{"id", o.id}, {"name", o.name}, {"class", static_cast<int>(o.cls)}});
  }
  return Json{{"layout", "uint16 object id, uint16 class id per pixel, little-endian"},
              {"classes", classes},
              {"objects", objects}};
}

bool FrameStream::parse_keys(const Json& request, const render::FrameCamera& info,
                             std::vector<render::EncodingKey>* keys, OpReply* reply) const {
  auto fail = [&](ApiError c, std::string m) {
    reply->fail(c, std::move(m));
    return false;
  };
  // "format" (one image) or "modalities" (a list of them), each named once
  keys->clear();
  const auto f = request.find("format");
  const auto mods = request.find("modalities");
  if (f != request.end() && mods != request.end()) {
    return fail(ApiError::kBadField, "give \"format\" or \"modalities\", not both");
  }
  if (mods != request.end()) {
    if (!mods->is_array() || mods->empty() || mods->size() > kMaxModalities) {
      return fail(
          ApiError::kBadField,
          "\"modalities\" must be a list of 1 to 5 of \"rgb\", \"grey\", \"jpeg\", \"depth\", "
          "\"segmentation\"");
    }
    for (const Json& m : *mods) {
      const auto e =
          m.is_string() ? render::encoding_from_name(m.get<std::string>()) : std::nullopt;
      if (!e) {
        return fail(ApiError::kBadField,
                    "unknown modality " + dump(m) +
                        " in \"modalities\" (rgb, grey, jpeg, depth, segmentation)");
      }
      if (std::any_of(keys->begin(), keys->end(),
                      [&](const render::EncodingKey& k) { return k.encoding == *e; })) {
        return fail(ApiError::kBadField,
                    "modality " + dump(m) + " is named twice in \"modalities\"");
      }
      keys->push_back({*e, 0});
    }
    std::sort(keys->begin(), keys->end(),
              [](const render::EncodingKey& a, const render::EncodingKey& b) {
                return a.encoding < b.encoding;
              });
  } else {
    render::EncodingKey key;
    if (f != request.end()) {
      const auto e =
          f->is_string() ? render::encoding_from_name(f->get<std::string>()) : std::nullopt;
      if (!e) {
        return fail(
            ApiError::kBadField,
            "\"format\" must be \"rgb\", \"grey\", \"jpeg\", \"depth\" or \"segmentation\"");
      }
      key.encoding = *e;
    }
    keys->push_back(key);
  }

  // what the camera gives (its modalities); JPEG is of its colour image
  const render::Modalities& has = info.modalities;
  for (const render::EncodingKey& k : *keys) {
    if (!render::gives(has, k.encoding)) {
      return fail(ApiError::kBadField, "camera '" + info.name + "' gives no " +
                                           render::encoding_name(k.encoding) + " (it gives " +
                                           modality_list(has).dump() +
                                           "; the world's uavsim:camera text or --camera " +
                                           info.name + ":modalities=... sets what it gives)");
    }
  }

  // JPEG quality
  const auto jpeg = std::find_if(keys->begin(), keys->end(), [](const render::EncodingKey& k) {
    return k.encoding == render::Encoding::kJpeg;
  });
  if (auto q = request.find("quality"); q != request.end()) {
    if (jpeg == keys->end())
      return fail(ApiError::kBadField, "\"quality\" applies to \"jpeg\" only");
    if (!q->is_number() || q->get<double>() < 1 || q->get<double>() > 100 ||
        std::floor(q->get<double>()) != q->get<double>()) {
      return fail(ApiError::kBadField, "\"quality\" must be an integer in [1, 100]");
    }
    jpeg->quality = static_cast<int>(q->get<double>());
  } else if (jpeg != keys->end()) {
    jpeg->quality = kDefaultJpegQuality;
  }

  // a capture must fit the connection's output limit (JPEG counted as RGB, its worst case)
  size_t bytes = 0;
  const size_t pixels = static_cast<size_t>(info.width_px) * static_cast<size_t>(info.height_px);
  for (const render::EncodingKey& k : *keys) {
    bytes += pixels * static_cast<size_t>(k.encoding == render::Encoding::kJpeg
                                              ? 3
                                              : render::bytes_per_pixel(k.encoding));
  }
  if (bytes > kMaxCaptureBytes) {
    return fail(ApiError::kBadField,
                "a capture of camera '" + info.name + "' with these modalities is too large: " +
                    std::to_string(bytes) + " bytes at " + std::to_string(info.width_px) + "x" +
                    std::to_string(info.height_px) + ", at most " +
                    std::to_string(kMaxCaptureBytes) +
                    " (ask for fewer modalities, or give the camera a smaller size)");
  }
  return true;
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

void FrameStream::op_list(const Json&, OpReply* reply) const {
  Json list = Json::array();
  for (size_t i = 0; i < service_.cameras().size(); ++i)
    list.push_back(camera_json(static_cast<int>(i)));
  reply->result = {{"cameras", list}};
}

std::optional<int> FrameStream::camera_field(const Json& request, OpReply* reply) const {
  auto cam_it = request.find("camera");
  if (cam_it == request.end()) {
    reply->fail(ApiError::kMissingField, "\"camera\" (a camera name) is required");
    return std::nullopt;
  }
  if (!cam_it->is_string()) {
    reply->fail(ApiError::kBadField, "\"camera\" must be a camera name (a string)");
    return std::nullopt;
  }
  const std::string name = cam_it->get<std::string>();
  const std::optional<int> camera = service_.find(name);
  if (!camera) {
    std::string names;
    for (const render::FrameCamera& c : service_.cameras())
      names += (names.empty() ? "" : ", ") + c.name;
    reply->fail(ApiError::kBadField, "no camera named '" + name +
                                         "' (cameras: " + (names.empty() ? "none" : names) + ")");
  }
  return camera;
}

void FrameStream::op_unsubscribe(uint64_t conn, const Json& request, OpReply* reply) {
  const std::optional<int> camera = camera_field(request, reply);
  if (!camera) return;
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
  reply->result = {{"camera", service_.cameras()[static_cast<size_t>(*camera)].name},
                   {"subscribed", sub != nullptr},
                   {"delivered", sub ? sub->delivered.load() : 0},
                   {"dropped", sub ? sub->dropped.load() : 0}};
}

void FrameStream::op_subscribe(uint64_t conn, const Json& request, OpReply* reply) {
  const std::optional<int> camera = camera_field(request, reply);
  if (!camera) return;
  const render::FrameCamera& info = service_.cameras()[static_cast<size_t>(*camera)];
  const std::string& name = info.name;
  std::vector<render::EncodingKey> keys;
  if (!parse_keys(request, info, &keys, reply)) return;
  int every = 1;
  if (auto f = request.find("fps"); f != request.end()) {
    const std::optional<int> whole =
        frame_divisor(info.fps_hz, f->is_number() ? f->get<double>() : -1.0);
    if (!whole) {
      return reply->fail(ApiError::kBadField, "\"fps\" must be camera '" + name + "''s fps (" +
                                                  dump(Json(info.fps_hz)) +
                                                  ") divided by a whole number up to " +
                                                  std::to_string(kMaxFrameDivisor));
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
  sub->keys = keys;
  sub->every = every;
  mine[*camera] = sub;
  Json names = Json::array();
  Json quality = nullptr;
  for (const render::EncodingKey& k : keys) {
    names.push_back(render::encoding_name(k.encoding));
    if (k.encoding == render::Encoding::kJpeg) quality = k.quality;
  }
  Json& result = reply->result;
  result = {{"camera", name},
            {"format", render::encoding_name(keys.front().encoding)},
            {"modalities", names},
            {"fps", info.fps_hz / every},
            {"quality", quality},
            {"width", info.width_px},
            {"height", info.height_px},
            {"intrinsics",
             {{"fx", info.fx_px}, {"fy", info.fy_px}, {"cx", info.cx_px}, {"cy", info.cy_px}}},
            {"every", every}};
  for (const render::EncodingKey& k : keys) {
    if (k.encoding == render::Encoding::kDepth) result["depth"] = depth_json(info);
    if (k.encoding == render::Encoding::kSegmentation) result["segmentation"] = segmentation_json();
  }
}

void FrameStream::op_blackout(const Json& request, OpReply* reply) {
  const double now_s = sim_.time_s();
  auto fail = [&](ApiError c, std::string m) { reply->fail(c, std::move(m)); };
  auto cam_it = request.find("camera");
  if (cam_it == request.end())
    return fail(ApiError::kMissingField, "\"camera\" (a camera name) is required");
  const std::optional<int> camera =
      cam_it->is_string() ? service_.find(cam_it->get<std::string>()) : std::nullopt;
  if (!camera) return fail(ApiError::kBadField, "\"camera\" must name a camera of camera_list");
  auto d = request.find("duration_s");
  if (d == request.end()) return fail(ApiError::kMissingField, "\"duration_s\" is required");
  // at most a day of sim time: the end stays an exact integer of microseconds
  constexpr double kMaxBlackout_s = 86400.0;
  if (!d->is_number() || !(d->get<double>() >= 0.0) || d->get<double>() > kMaxBlackout_s) {
    return fail(ApiError::kBadField, "\"duration_s\" must be a number of seconds in [0, 86400]");
  }
  const int64_t from_us = std::llround(now_s * 1e6);
  const int64_t until_us = from_us + std::llround(d->get<double>() * 1e6);
  {
    std::lock_guard<std::mutex> lock(mutex_);
    blackouts_[*camera] = {from_us, until_us};
  }
  reply->result = {{"camera", cam_it->get<std::string>()},
                   {"from_s", from_us * 1e-6},
                   {"until_s", until_us * 1e-6}};
}

void FrameStream::clear_blackouts() {
  std::lock_guard<std::mutex> lock(mutex_);
  blackouts_.clear();
}

void FrameStream::want(int camera, int64_t index, int64_t,
                       std::vector<render::EncodingKey>* encodings, bool* must_deliver) {
  std::vector<Pending> takers;
  for (auto& [conn, cams] : subs_) {
    auto it = cams.find(camera);
    if (it == cams.end() || index % it->second->every != 0) continue;
    Pending p;
    p.sub = it->second;
    p.seq = p.sub->next_seq++;
    p.must = is_lockstep_ && is_lockstep_(conn);
    *must_deliver = *must_deliver || p.must;
    encodings->insert(encodings->end(), p.sub->keys.begin(), p.sub->keys.end());
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
  const Json pose = {
      {"position_enu_m",
       {frame.position_enu_m.x(), frame.position_enu_m.y(), frame.position_enu_m.z()}},
      {"R_enu_cam", R}};
  const Json intrinsics = {{"fx", c.fx_px}, {"fy", c.fy_px}, {"cx", c.cx_px}, {"cy", c.cy_px}};
  const auto blackout = blackouts_.find(frame.camera);
  const bool black = blackout != blackouts_.end() && frame.stamp_us >= blackout->second.first &&
                     frame.stamp_us < blackout->second.second;
  std::vector<std::pair<render::EncodingKey, std::shared_ptr<const std::string>>> black_images;
  // a blacked-out camera: the same frame, every pixel black and no depth (encoded once per
  // encoding); segmentation is ground truth of the scene, not of the sensor, and stays
  auto image = [&](const render::EncodingKey& key) -> const std::string* {
    const std::string* bytes = frame.image(key);
    if (!black || bytes == nullptr || key.encoding == render::Encoding::kSegmentation) return bytes;
    auto it = std::find_if(black_images.begin(), black_images.end(),
                           [&](const auto& b) { return b.first == key; });
    if (it == black_images.end()) {
      black_images.emplace_back(key, render::encode_black_frame(c.width_px, c.height_px, key));
      it = std::prev(black_images.end());
    }
    return it->second.get();
  };
  for (Pending& p : takers) {
    Sub& sub = *p.sub;
    if (!sub.active) continue;
    std::vector<const std::string*> parts;
    size_t bytes = 0;
    for (const render::EncodingKey& key : sub.keys) {
      parts.push_back(image(key));
      if (parts.back() == nullptr) break;
      bytes += parts.back()->size();
    }
    if (parts.empty() || parts.back() == nullptr) continue;
    // all images of a capture or none: a slow reader loses whole captures
    if (!p.must && server_.pending_bytes(sub.conn) > kMaxQueuedFrames * bytes) {
      ++sub.dropped;
      continue;
    }
    // what this subscription lost before this frame: frames reach a subscription in seq order, so
    // every earlier seq not delivered was dropped. (The running total `sub.dropped` may already
    // count frames after this one, which the renderer refused while this one was still being
    // rendered.)
    const uint64_t delivered = sub.delivered.load();
    const uint64_t dropped_before = p.seq > delivered ? p.seq - delivered : 0;
    Json names = Json::array();
    for (const render::EncodingKey& key : sub.keys)
      names.push_back(render::encoding_name(key.encoding));
    // one header line and its bytes per image, all in one send: nothing comes between the parts
    std::string message;
    message.reserve(bytes + 1024 * parts.size());
    for (size_t i = 0; i < parts.size(); ++i) {
      const render::Encoding e = sub.keys[i].encoding;
      Json header = {{"event", "frame"},
                     {"camera", c.name},
                     {"vehicle", c.vehicle >= 0 ? Json(c.vehicle_name) : Json(nullptr)},
                     {"seq", p.seq},
                     {"dropped", dropped_before},
                     {"stamp", frame.stamp_s},
                     {"stamp_us", frame.stamp_us},
                     {"width", c.width_px},
                     {"height", c.height_px},
                     {"format", render::encoding_name(e)},
                     {"bytes", parts[i]->size()},
                     {"part", i},
                     {"parts", parts.size()},
                     {"modalities", names},
                     {"intrinsics", intrinsics},
                     {"pose", pose}};
      if (e == render::Encoding::kDepth) {
        header["near_m"] = c.depth_near_m;
        header["far_m"] = c.depth_far_m;
      }
      message += dump(header);
      message += '\n';
      message += *parts[i];
    }
    // a frame wakes a lockstep client even after its quiet done: it may run its vision on it while
    // the simulation steps on to its tick
    if (server_.send(sub.conn, message, /*work_ahead=*/true)) ++sub.delivered;
  }
}

}  // namespace uavsim::server::api
