#include "api/radio_ops.hpp"

#include <cmath>
#include <cstdio>
#include <functional>
#include <span>

#include "api/request_fields.hpp"
#include "api/vehicle_arg.hpp"
#include "uavsim/common/base64.hpp"

namespace uavsim::server::api {

namespace {

constexpr double kPortLimit = 65535;

constexpr FieldSpec kSendFields[] = {{"vehicle", FieldType::kIndexOrName},
                                     {"to", FieldType::kIndexOrName},
                                     {"data_b64", FieldType::kString}};
constexpr FieldSpec kSubscribeFields[] = {{"vehicle", FieldType::kIndexOrName},
                                          {"batch", FieldType::kBoolean}};
constexpr FieldSpec kVehicleFields[] = {{"vehicle", FieldType::kIndexOrName}};
// radio_config's numbers are checked here for type and finiteness; their own ranges by the channel
// (RadioChannel::set_config), which names the range it refuses
constexpr FieldSpec kConfigFields[] = {
    {"range_m", FieldType::kNumber},
    {"tx_power_dbm", FieldType::kNumber},
    {"sensitivity_dbm", FieldType::kNumber},
    {"reference_loss_db", FieldType::kNumber},
    {"path_loss_exponent", FieldType::kNumber},
    {"shadowing_sigma_db", FieldType::kNumber},
    {"loss", FieldType::kNumber},
    {"latency_s", FieldType::kNumber},
    {"send_spread_s", FieldType::kNumber},
    {"slot_s", FieldType::kNumber},
    {"period_s", FieldType::kNumber},
    {"tdma", FieldType::kBoolean},
    {"collisions", FieldType::kBoolean},
    {"model", FieldType::kString},
    {"technology", FieldType::kString},
    {"max_queue_frames", FieldType::kNumber, 1, 1000000},
    {"mac_header_bytes", FieldType::kNumber, 0, radio::kMaxMacHeaderBytes},
    {"obstacle_loss_db", FieldType::kArray}};
constexpr FieldSpec kLinkOpenFields[] = {{"vehicle", FieldType::kIndexOrName},
                                         {"uav_port", FieldType::kNumber, 0, kPortLimit},
                                         {"gcs_port", FieldType::kNumber, 0, kPortLimit},
                                         {"gcs_target_port", FieldType::kNumber, 0, kPortLimit},
                                         {"gcs_target_host", FieldType::kString}};
constexpr FieldSpec kLinkImpairFields[] = {{"vehicle", FieldType::kIndexOrName},
                                           {"loss", FieldType::kNumber, 0, 1},
                                           {"latency_s", FieldType::kNumber, 0, 3600},
                                           {"outage_s", FieldType::kNumber, 0, 1e6}};

// A whole-number field whose range its FieldSpec has checked: true with *out set (left alone when
// absent), or false with reply failed for a fraction.
template <typename T>
bool whole_field(const nlohmann::json& request, const char* key, std::optional<T>* out,
                 OpReply* reply) {
  const auto it = request.find(key);
  if (it == request.end()) return true;
  if (!it->is_number_integer() && !it->is_number_unsigned()) {
    reply->fail(ApiError::kBadField, std::string("\"") + key + "\" must be a whole number");
    return false;
  }
  *out = static_cast<T>(it->get<int64_t>());
  return true;
}

}  // namespace

RadioOps::RadioOps(sim::Simulation& sim, radio::SimRadio& radio, radio::GcsRelaySet* relays,
                   GcsTargetPolicy policy)
    : sim_(sim), radio_(radio), relays_(relays), policy_(std::move(policy)) {}

void RadioOps::register_ops(OpTable& table) {
  const OpRegistrar<RadioOps> radio(table, this, "radio");
  radio("radio_send", &RadioOps::op_send, kSendFields);
  radio("radio_subscribe", &RadioOps::op_subscribe, kSubscribeFields);
  radio("radio_unsubscribe", &RadioOps::op_unsubscribe, kVehicleFields);
  radio("radio_stats", &RadioOps::op_stats, kVehicleFields);
  radio("radio_config", &RadioOps::op_config, kConfigFields);
  const OpRegistrar<RadioOps> link(table, this, "gcs_link");
  link("gcs_link_open", &RadioOps::op_link_open, kLinkOpenFields);
  link("gcs_link_impair", &RadioOps::op_link_impair, kLinkImpairFields);
  link("gcs_link_stats", &RadioOps::op_link_stats, kVehicleFields);
}

RadioOps::Json RadioOps::config_json() const {
  const radio::RadioConfig& c = radio_.model().config();
  return Json{{"backend", radio_.model().backend_name()},
              {"technology", radio::technology_name(c.technology)},
              {"model", radio::propagation_name(c.propagation)},
              {"range_m", c.range_m},
              {"tx_power_dbm", c.tx_power_dbm},
              {"sensitivity_dbm", c.sensitivity_dbm},
              {"reference_loss_db", c.reference_loss_db},
              {"path_loss_exponent", c.path_loss_exponent},
              {"shadowing_sigma_db", c.shadowing_sigma_db},
              {"loss", c.loss_probability},
              {"latency_s", c.latency_s},
              {"send_spread_s", c.send_spread_s},
              {"tdma", c.tdma},
              {"slot_s", c.slot_s},
              {"period_s", c.period_s},
              {"collisions", c.collisions},
              {"max_queue_frames", c.max_queue_frames},
              {"max_frame_bytes", radio_.model().max_payload_bytes()},
              {"mac_header_bytes", c.mac_header_bytes},
              {"obstacle_loss_db", c.obstacle_loss_db}};
}

void RadioOps::op_config(uint64_t, const Json& request, OpReply* reply) {
  // every field optional, each of its type (kConfigFields); nothing is applied unless all are good
  radio::RadioConfig c = radio_.model().config();
  const std::pair<const char*, double*> numbers[] = {{"range_m", &c.range_m},
                                                     {"tx_power_dbm", &c.tx_power_dbm},
                                                     {"sensitivity_dbm", &c.sensitivity_dbm},
                                                     {"reference_loss_db", &c.reference_loss_db},
                                                     {"path_loss_exponent", &c.path_loss_exponent},
                                                     {"shadowing_sigma_db", &c.shadowing_sigma_db},
                                                     {"loss", &c.loss_probability},
                                                     {"latency_s", &c.latency_s},
                                                     {"send_spread_s", &c.send_spread_s},
                                                     {"slot_s", &c.slot_s},
                                                     {"period_s", &c.period_s}};
  for (const auto& [key, field] : numbers) {
    if (const auto v = number_field(request, key)) *field = *v;
  }
  if (const auto v = bool_field(request, "tdma")) c.tdma = *v;
  if (const auto v = bool_field(request, "collisions")) c.collisions = *v;
  if (const auto name = string_field(request, "model")) {
    const auto p = radio::propagation_from_name(*name);
    if (!p)
      return reply->fail(ApiError::kBadField, "\"model\" must be \"range\" or \"log_distance\"");
    c.propagation = *p;
  }
  if (const auto name = string_field(request, "technology")) {
    const auto t = radio::technology_from_name(*name);
    if (!t)
      return reply->fail(ApiError::kBadField, "\"technology\" must be \"802.15.4\" or \"802.11\"");
    c.technology = *t;
  }
  std::optional<size_t> queue_frames, header_bytes;
  if (!whole_field(request, "max_queue_frames", &queue_frames, reply) ||
      !whole_field(request, "mac_header_bytes", &header_bytes, reply)) {
    return;
  }
  if (queue_frames) c.max_queue_frames = *queue_frames;
  if (header_bytes) c.mac_header_bytes = *header_bytes;
  if (auto it = request.find("obstacle_loss_db"); it != request.end()) {
    // one loss per MuJoCo geom group, in dB; groups not given block nothing
    bool ok = it->size() <= radio::kGeomGroups;
    for (size_t g = 0; ok && g < it->size(); ++g) {
      ok =
          (*it)[g].is_number() && (*it)[g].get<double>() >= 0.0 && (*it)[g].get<double>() <= 1000.0;
    }
    if (!ok) {
      return reply->fail(
          ApiError::kBadField,
          "\"obstacle_loss_db\" must be an array of up to 6 numbers in [0, 1000] (dB per "
          "geom group)");
    }
    c.obstacle_loss_db.fill(0.0);
    for (size_t g = 0; g < it->size(); ++g) c.obstacle_loss_db[g] = (*it)[g].get<double>();
  }
  std::string why;
  if (!radio_.model().set_config(c, &why)) return reply->fail(ApiError::kBadField, why);
  reply->result = config_json();
}

void RadioOps::op_send(uint64_t, const Json& request, OpReply* reply) {
  const auto from = required_vehicle(sim_, request, reply, "the sender");
  if (!from) return;
  const auto to_field = request.find("to");
  if (to_field == request.end()) {
    return reply->fail(ApiError::kMissingField, "\"to\" (a vehicle or \"broadcast\") is required");
  }
  int to = radio::kBroadcast;
  if (!(to_field->is_string() && to_field->get<std::string>() == "broadcast")) {
    const auto v = vehicle_index(sim_, *to_field, reply);
    if (!v) return;
    if (*v == *from)
      return reply->fail(ApiError::kBadField, "a vehicle cannot send a frame to itself");
    to = static_cast<int>(*v);
  }
  // the frame: raw bytes from a request ring's binary form (docs/protocol.md), base64 otherwise
  const size_t max_bytes = radio_.model().max_payload_bytes();
  const char* technology = radio::technology_name(radio_.model().config().technology);
  std::optional<std::vector<uint8_t>> decoded;
  const std::vector<uint8_t>* data = nullptr;
  if (const auto raw = request.find("data"); raw != request.end() && raw->is_binary()) {
    data = &raw->get_binary();
  } else {
    const auto data_b64 = string_field(request, "data_b64");
    if (!data_b64)
      return reply->fail(ApiError::kMissingField, "\"data_b64\" (the frame, base64) is required");
    // a bound before decoding: n bytes are 4 * ceil(n / 3) characters (127: 172; 1500: 2000)
    if (data_b64->size() > 4 * ((max_bytes + 2) / 3)) {
      return reply->fail(
          ApiError::kFrameTooLarge,
          "a frame is at most " + std::to_string(max_bytes) + " bytes (" + technology + ")");
    }
    decoded = common::base64_decode(*data_b64);
    if (!decoded) return reply->fail(ApiError::kBadBase64, "\"data_b64\" is not valid base64");
    data = &*decoded;
  }
  if (data->empty()) return reply->fail(ApiError::kBadField, "a frame carries at least one byte");
  if (data->size() > max_bytes) {
    return reply->fail(ApiError::kFrameTooLarge,
                       "a frame is at most " + std::to_string(max_bytes) + " bytes (" + technology +
                           " on the " + radio_.model().backend_name() + " backend), got " +
                           std::to_string(data->size()));
  }
  if (const std::string why = radio_.model().failure(); !why.empty()) {
    return reply->fail(ApiError::kNotAvailable, "the radio failed: " + why);
  }
  const radio::SendResult r = radio_.send(*from, to, *data);
  if (!r.seq) {
    if (r.error == radio::Error::kQueueFull) {
      // the sender offers more than its airtime carries: said with what would fit, and counted
      const radio::RadioConfig& c = radio_.model().config();
      // 802.15.4's airtime at 250 kbit/s (802.11's depends on its contention: not said)
      std::string carries;
      if (c.technology == radio::Technology::k802154) {
        char ms[64];
        std::snprintf(ms, sizeof(ms), "%.2f ms",
                      1e3 * radio::airtime_s(data->size() + c.mac_header_bytes));
        carries = std::string(": the channel carries one such frame per ") + ms +
                  (c.tdma ? " in the sender's own TDMA slots" : "");
      }
      return reply->fail(ApiError::kQueueFull,
                         "vehicle " + std::to_string(*from) + " has " +
                             std::to_string(radio_.model().queued(*from)) +
                             " frames waiting to go on air (max_queue_frames " +
                             std::to_string(c.max_queue_frames) + ")" + carries +
                             "; this frame is dropped (radio_stats: refused)");
    }
    return reply->fail(ApiError::kBadField, radio::error_name(r.error));
  }
  reply->result = {{"vehicle", *from}, {"seq", *r.seq}, {"time_s", sim_.time_s()}};
}

void RadioOps::op_subscribe(uint64_t conn, const Json& request, OpReply* reply) {
  subscription_op(conn, request, true, reply);
}

void RadioOps::op_unsubscribe(uint64_t conn, const Json& request, OpReply* reply) {
  if (has_field(request, "batch")) {
    return reply->fail(ApiError::kBadField,
                       "\"batch\" is a boolean of radio_subscribe (one radio_batch event a gate)");
  }
  subscription_op(conn, request, false, reply);
}

void RadioOps::subscription_op(uint64_t conn, const Json& request, bool subscribe, OpReply* reply) {
  // one vehicle, or every vehicle without "vehicle"
  std::set<size_t> which;
  if (has_field(request, "vehicle")) {
    const auto v = optional_vehicle(sim_, request, reply);
    if (!v) return;
    which.insert(*v);
  } else {
    for (size_t i = 0; i < sim_.vehicle_count(); ++i) which.insert(i);
  }
  Subscription& sub = subscriptions_[conn];
  // the connection's delivery form, for all its vehicles (radio_subscribe only: kSubscribeFields)
  if (const auto batch = bool_field(request, "batch")) sub.batch = *batch;
  for (size_t v : which) {
    if (subscribe) {
      sub.vehicles.insert(v);
    } else {
      sub.vehicles.erase(v);
    }
  }
  reply->result = {
      {"vehicles", Json(std::vector<size_t>(sub.vehicles.begin(), sub.vehicles.end()))},
      {"batch", sub.batch},
      {"max_frame_bytes", radio_.model().max_payload_bytes()},
      {"time_s", sim_.time_s()}};
}

void RadioOps::op_stats(uint64_t, const Json& request, OpReply* reply) {
  std::optional<size_t> only;
  if (has_field(request, "vehicle")) {
    only = optional_vehicle(sim_, request, reply);
    if (!only) return;
  }
  const radio::RadioChannel& m = radio_.model();
  Json vehicles = Json::array();
  Json links = Json::array();
  for (size_t a = 0; a < m.vehicle_count(); ++a) {
    if (!only || *only == a) {
      vehicles.push_back({{"vehicle", a},
                          {"name", sim_.vehicle_name(a)},
                          {"transmitted", m.transmitted(a)},
                          {"queued", m.queued(a)},
                          {"refused", radio_.refused(a)},
                          {"channel_access_failures", m.channel_access_failures(a)}});
    }
    for (size_t b = 0; b < m.vehicle_count(); ++b) {
      const radio::LinkStats& s = m.link(a, b);
      if (s.sent == 0 || (only && *only != a && *only != b)) continue;
      links.push_back({{"from", a},
                       {"to", b},
                       {"sent", s.sent},
                       {"delivered", s.delivered},
                       {"lost", s.lost},
                       {"collided", s.collided},
                       {"out_of_range", s.out_of_range},
                       {"no_ack", s.no_ack}});
    }
  }
  reply->result = {{"time_s", sim_.time_s()},
                   {"backend", m.backend_name()},
                   {"max_frame_bytes", m.max_payload_bytes()},
                   {"failure", m.failure()},
                   {"vehicles", vehicles},
                   {"links", links},
                   {"inbox_overflows", radio_.inbox_overflows()}};
}

// ---------------------------------------------------------------------------------------------------
// the ground-station link relay (seed 6.3)

RadioOps::Json RadioOps::relay_json(size_t vehicle, radio::GcsRelay& r) const {
  const radio::RelayImpairment& i = r.impairment();
  const radio::RelayStats& s = r.stats();
  return Json{
      {"vehicle", vehicle},
      {"uav_port", r.uav_port()},
      {"gcs_port", r.gcs_port()},
      {"loss", i.loss_probability},
      {"latency_s", i.latency_s},
      {"outage_until_s", std::isfinite(i.outage_until_s) ? Json(i.outage_until_s) : Json(nullptr)},
      {"to_gcs_forwarded", s.to_gcs_forwarded},
      {"to_gcs_dropped", s.to_gcs_dropped},
      {"to_uav_forwarded", s.to_uav_forwarded},
      {"to_uav_dropped", s.to_uav_dropped},
      {"backend", relays_->backend_name()},
      {"time_s", sim_.time_s()}};
}

std::optional<size_t> RadioOps::relay_vehicle(const Json& request, OpReply* reply) const {
  if (relays_ == nullptr) {
    reply->fail(ApiError::kNotAvailable, "this server has no GCS link relay");
    return std::nullopt;
  }
  return required_vehicle(sim_, request, reply);
}

radio::GcsRelay* RadioOps::open_relay(size_t vehicle, OpReply* reply) const {
  radio::GcsRelay* r = relays_->relay(vehicle);
  if (r == nullptr) {
    reply->fail(ApiError::kNotAvailable,
                "vehicle " + std::to_string(vehicle) + " has no relay (gcs_link_open)");
  }
  return r;
}

void RadioOps::op_link_open(uint64_t conn, const Json& request, OpReply* reply) {
  const auto v = relay_vehicle(request, reply);
  if (!v) return;
  std::optional<uint16_t> uav_port, gcs_port, target_port;
  if (!whole_field(request, "uav_port", &uav_port, reply) ||
      !whole_field(request, "gcs_port", &gcs_port, reply) ||
      !whole_field(request, "gcs_target_port", &target_port, reply)) {
    return;
  }
  // the relay sends UDP datagrams: to the requesting client's own host only, unless the server
  // allows others (a relay aimed at a third host would make the server a traffic source)
  std::optional<std::string> target_host = string_field(request, "gcs_target_host");
  if (!policy_.allow_remote) {
    const std::string peer = policy_.peer_address ? policy_.peer_address(conn) : std::string();
    if (!target_host) {
      target_host = peer;
    } else if (*target_host != peer) {
      return reply->fail(ApiError::kForbidden,
                         "gcs_target_host must be this client's own address (" + peer +
                             ") unless the server runs with --allow-remote-gcs");
    }
  }
  std::string why;
  radio::GcsRelay* r =
      relays_->open(*v, uav_port.value_or(0), gcs_port.value_or(0), target_host, target_port, &why);
  if (r == nullptr) return reply->fail(ApiError::kIoError, why);
  reply->result = relay_json(*v, *r);
}

void RadioOps::op_link_impair(uint64_t, const Json& request, OpReply* reply) {
  const auto v = relay_vehicle(request, reply);
  if (!v) return;
  radio::GcsRelay* r = open_relay(*v, reply);
  if (r == nullptr) return;
  // each in its range (kLinkImpairFields); absent: loss and latency as they are, no outage
  r->impair(number_field(request, "loss").value_or(r->impairment().loss_probability),
            number_field(request, "latency_s").value_or(r->impairment().latency_s),
            number_field(request, "outage_s").value_or(0.0), sim_.time_s());
  reply->result = relay_json(*v, *r);
}

void RadioOps::op_link_stats(uint64_t, const Json& request, OpReply* reply) {
  const auto v = relay_vehicle(request, reply);
  if (!v) return;
  if (radio::GcsRelay* r = open_relay(*v, reply)) reply->result = relay_json(*v, *r);
}

void RadioOps::on_gate(const Send& send, const InLockstep& in_lockstep) {
  // frames that arrived by now go out before this gate announces its ticks (a lockstep batch
  // subscriber's just before its own tick); frames sent at this time go on air at the step, once
  // every lockstep client has sent its own (deterministic draws)
  radio_.advance(false);
  std::vector<radio::Delivery> arrived = radio_.take_deliveries();
  if (!arrived.empty() && !subscriptions_.empty())
    queue_deliveries(std::move(arrived), send, in_lockstep);
  // what is held for a connection that has left lockstep (or never joined) goes now
  for (auto it = held_binary_.begin(); it != held_binary_.end();) {
    const uint64_t conn = (it++)->first;
    if (!in_lockstep(conn)) send_held(conn, send);
  }
  for (auto it = held_.begin(); it != held_.end();) {
    const uint64_t conn = (it++)->first;
    if (!in_lockstep(conn)) send_held(conn, send);
  }
}

void RadioOps::before_tick(uint64_t conn, const Send& send) {
  // a shared-memory stream's frames go in the tick's record, which the server writes next
  if (const auto it = held_binary_.find(conn); it != held_binary_.end() && shm_ != nullptr) {
    shm_->set_tick_radio(conn, std::move(it->second));
    held_binary_.erase(it);
  }
  send_held(conn, send);
}

namespace {
// [to, from, seq, broadcast, time, sent_time, data_b64]: a radio event's fields, keys once
nlohmann::json compact_frame(const radio::Delivery& d, const std::string& data_b64) {
  return nlohmann::json::array({d.to, d.from, d.seq, d.broadcast, d.time_s, d.queued_s, data_b64});
}
}  // namespace

void RadioOps::send_held(uint64_t conn, const Send& send) {
  // frames held as such (a connection that has left lockstep on a shared-memory stream) go as a
  // line
  if (const auto b = held_binary_.find(conn); b != held_binary_.end()) {
    Json& batch = held_[conn];
    if (batch.is_null()) batch = Json::array();
    for (const radio::Delivery& d : b->second)
      batch.push_back(compact_frame(d, common::base64_encode(d.data)));
    held_binary_.erase(b);
  }
  const auto it = held_.find(conn);
  if (it == held_.end()) return;
  Json frames = std::move(it->second);
  held_.erase(it);
  send(conn,
       Json{{"event", "radio_batch"}, {"time", sim_.time_s()}, {"frames", std::move(frames)}});
}

void RadioOps::queue_deliveries(std::vector<radio::Delivery>&& arrived, const Send& send,
                                const InLockstep& in_lockstep) {
  // a broadcast is one delivery per receiver with the same bytes: encoded once per frame
  std::map<std::pair<size_t, uint64_t>, std::string> encoded;  // (from, seq) -> base64
  auto data_b64 = [&](const radio::Delivery& d) -> const std::string& {
    auto [it, fresh] = encoded.try_emplace({d.from, d.seq});
    if (fresh) it->second = common::base64_encode(d.data);
    return it->second;
  };
  // how each subscriber takes its frames, decided once a call (hundreds of frames a tick for a
  // flock), and the subscribers of each receiving vehicle in connection order
  enum class Mode { kBinary, kBatch, kEvent };
  struct Target {
    uint64_t conn;
    Mode mode;
  };
  std::map<size_t, std::vector<Target>> targets;
  for (const radio::Delivery& d : arrived) targets.try_emplace(d.to);
  for (const auto& [conn, sub] : subscriptions_) {
    const Mode mode = !sub.batch ? Mode::kEvent
                      : (shm_ != nullptr && in_lockstep(conn) && shm_->attached(conn))
                          ? Mode::kBinary
                          : Mode::kBatch;
    for (auto& [vehicle, list] : targets) {
      if (sub.vehicles.count(vehicle) != 0) list.push_back({conn, mode});
    }
  }
  for (radio::Delivery& d : arrived) {
    const std::vector<Target>& list = targets[d.to];
    Json event;  // built once, for the first subscriber that hears it
    Json compact;
    for (size_t k = 0; k < list.size(); ++k) {
      const uint64_t conn = list[k].conn;
      switch (list[k].mode) {
        case Mode::kBinary: {
          // no base64: the tick record carries the bytes (the last subscriber takes them)
          std::vector<radio::Delivery>& held = held_binary_[conn];
          if (k + 1 == list.size()) {
            held.push_back(std::move(d));
          } else {
            held.push_back(d);
          }
          break;
        }
        case Mode::kBatch: {
          if (compact.is_null()) compact = compact_frame(d, data_b64(d));
          Json& batch = held_[conn];
          if (batch.is_null()) batch = Json::array();
          batch.push_back(compact);
          break;
        }
        case Mode::kEvent: {
          if (event.is_null()) {
            event = {{"event", "radio"},
                     {"to", d.to},
                     {"from", d.from},
                     {"time", d.time_s},
                     {"seq", d.seq},
                     {"broadcast", d.broadcast},
                     {"sent_time", d.queued_s},
                     {"data_b64", data_b64(d)}};
          }
          send(conn, event);
          break;
        }
      }
    }
  }
}

void RadioOps::on_disconnect(uint64_t conn) {
  subscriptions_.erase(conn);
  held_.erase(conn);
  held_binary_.erase(conn);
}

}  // namespace uavsim::server::api
