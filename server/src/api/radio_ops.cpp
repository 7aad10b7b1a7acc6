#include "api/radio_ops.hpp"

#include <cmath>
#include <functional>

#include "api/vehicle_arg.hpp"
#include "uavsim/common/base64.hpp"

namespace uavsim::server::api {

namespace {

bool set_error(std::string* code, std::string* message, const std::string& c,
               const std::string& m) {
  *code = c;
  *message = m;
  return false;
}

}  // namespace

RadioOps::RadioOps(sim::Simulation& sim, radio::SimRadio& radio, radio::GcsRelaySet* relays)
    : sim_(sim), radio_(radio), relays_(relays) {}

void RadioOps::register_ops(OpTable& table) {
  static constexpr std::string_view kRadio[] = {"radio_send", "radio_subscribe", "radio_unsubscribe",
                                                "radio_stats", "radio_config"};
  static constexpr std::string_view kGcsLink[] = {"gcs_link_open", "gcs_link_impair", "gcs_link_stats"};
  const auto handler = std::bind_front(&RadioOps::handle, this);
  table.add_named("radio", kRadio, handler);
  table.add_named("gcs_link", kGcsLink, handler);
}

std::optional<size_t> RadioOps::vehicle(const Json& value, std::string* code,
                                        std::string* message) const {
  return vehicle_index(sim_, value, code, message);
}

RadioOps::Json RadioOps::config_json() const {
  const radio::RadioConfig& c = radio_.model().config();
  return Json{{"backend", radio_.model().backend_name()},
              {"model", radio::propagation_name(c.propagation)},
              {"range_m", c.range_m},
              {"tx_power_dbm", c.tx_power_dbm},
              {"sensitivity_dbm", c.sensitivity_dbm},
              {"reference_loss_db", c.reference_loss_db},
              {"path_loss_exponent", c.path_loss_exponent},
              {"shadowing_sigma_db", c.shadowing_sigma_db},
              {"loss", c.loss_probability},
              {"latency_s", c.latency_s},
              {"tdma", c.tdma},
              {"slot_s", c.slot_s},
              {"period_s", c.period_s},
              {"collisions", c.collisions},
              {"max_queue_frames", c.max_queue_frames},
              {"max_frame_bytes", radio_.model().max_payload_bytes()},
              {"mac_header_bytes", c.mac_header_bytes},
              {"obstacle_loss_db", c.obstacle_loss_db}};
}

bool RadioOps::apply_config(const Json& request, std::string* code, std::string* message) {
  radio::RadioConfig c = radio_.model().config();
  // every field optional; a present field of the wrong type is an error, nothing is applied then
  const std::pair<const char*, double*> numbers[] = {{"range_m", &c.range_m},
                                                     {"tx_power_dbm", &c.tx_power_dbm},
                                                     {"sensitivity_dbm", &c.sensitivity_dbm},
                                                     {"reference_loss_db", &c.reference_loss_db},
                                                     {"path_loss_exponent", &c.path_loss_exponent},
                                                     {"shadowing_sigma_db", &c.shadowing_sigma_db},
                                                     {"loss", &c.loss_probability},
                                                     {"latency_s", &c.latency_s},
                                                     {"slot_s", &c.slot_s},
                                                     {"period_s", &c.period_s}};
  for (const auto& [key, field] : numbers) {
    auto it = request.find(key);
    if (it == request.end()) continue;
    if (!it->is_number())
      return set_error(code, message, "bad_field", std::string("\"") + key + "\" must be a number");
    *field = it->get<double>();
  }
  const std::pair<const char*, bool*> flags[] = {{"tdma", &c.tdma}, {"collisions", &c.collisions}};
  for (const auto& [key, field] : flags) {
    auto it = request.find(key);
    if (it == request.end()) continue;
    if (!it->is_boolean())
      return set_error(code, message, "bad_field",
                       std::string("\"") + key + "\" must be a boolean");
    *field = it->get<bool>();
  }
  if (auto it = request.find("model"); it != request.end()) {
    const auto p =
        it->is_string() ? radio::propagation_from_name(it->get<std::string>()) : std::nullopt;
    if (!p)
      return set_error(code, message, "bad_field",
                       "\"model\" must be \"range\" or \"log_distance\"");
    c.propagation = *p;
  }
  if (auto it = request.find("max_queue_frames"); it != request.end()) {
    if (!it->is_number_unsigned() || it->get<uint64_t>() > 1000000) {
      return set_error(code, message, "bad_field",
                       "\"max_queue_frames\" must be an integer in [1, 1000000]");
    }
    c.max_queue_frames = it->get<size_t>();
  }
  if (auto it = request.find("mac_header_bytes"); it != request.end()) {
    if (!it->is_number_unsigned() || it->get<uint64_t>() > radio::kMaxMacHeaderBytes) {
      return set_error(code, message, "bad_field",
                       "\"mac_header_bytes\" must be an integer in [0, " +
                           std::to_string(radio::kMaxMacHeaderBytes) + "]");
    }
    c.mac_header_bytes = it->get<size_t>();
  }
  if (auto it = request.find("obstacle_loss_db"); it != request.end()) {
    // one loss per MuJoCo geom group, in dB; groups not given block nothing
    bool ok = it->is_array() && it->size() <= radio::kGeomGroups;
    for (size_t g = 0; ok && g < it->size(); ++g) {
      ok =
          (*it)[g].is_number() && (*it)[g].get<double>() >= 0.0 && (*it)[g].get<double>() <= 1000.0;
    }
    if (!ok) {
      return set_error(
          code, message, "bad_field",
          "\"obstacle_loss_db\" must be an array of up to 6 numbers in [0, 1000] (dB per "
          "geom group)");
    }
    c.obstacle_loss_db.fill(0.0);
    for (size_t g = 0; g < it->size(); ++g) c.obstacle_loss_db[g] = (*it)[g].get<double>();
  }
  std::string why;
  if (!radio_.model().set_config(c, &why)) return set_error(code, message, "bad_field", why);
  return true;
}

bool RadioOps::handle(uint64_t conn, const std::string& op, const Json& request, Json* result,
                      std::string* code, std::string* message) {
  const auto vit = request.find("vehicle");
  if (op == "radio_send") {
    if (vit == request.end())
      return set_error(code, message, "missing_field", "\"vehicle\" (the sender) is required");
    const auto from = vehicle(*vit, code, message);
    if (!from) return false;
    const auto tit = request.find("to");
    if (tit == request.end()) {
      return set_error(code, message, "missing_field",
                       "\"to\" (a vehicle or \"broadcast\") is required");
    }
    int to = radio::kBroadcast;
    if (!(tit->is_string() && tit->get<std::string>() == "broadcast")) {
      const auto v = vehicle(*tit, code, message);
      if (!v) return false;
      if (*v == *from)
        return set_error(code, message, "bad_field", "a vehicle cannot send a frame to itself");
      to = static_cast<int>(*v);
    }
    const auto dit = request.find("data_b64");
    if (dit == request.end() || !dit->is_string()) {
      return set_error(code, message, "missing_field",
                       "\"data_b64\" (the frame, base64) is required");
    }
    // a generous bound before decoding: 127 bytes are 172 characters
    const size_t max_bytes = radio_.model().max_payload_bytes();
    if (dit->get_ref<const std::string&>().size() > 4 * radio::kMaxFrameBytes) {
      return set_error(code, message, "frame_too_large",
                       "a frame is at most " + std::to_string(max_bytes) + " bytes (802.15.4)");
    }
    const auto data = common::base64_decode(dit->get<std::string>());
    if (!data) return set_error(code, message, "bad_base64", "\"data_b64\" is not valid base64");
    if (data->empty())
      return set_error(code, message, "bad_field", "a frame carries at least one byte");
    if (data->size() > max_bytes) {
      return set_error(code, message, "frame_too_large",
                       "a frame is at most " + std::to_string(max_bytes) +
                           " bytes (802.15.4 on the " + radio_.model().backend_name() +
                           " backend), got " + std::to_string(data->size()));
    }
    if (const std::string why = radio_.model().failure(); !why.empty()) {
      return set_error(code, message, "not_available", "the radio failed: " + why);
    }
    const radio::SendResult r = radio_.send(*from, to, *data);
    if (!r.seq) {
      const bool full = r.error == radio::Error::kQueueFull;
      return set_error(code, message, full ? "queue_full" : "bad_field",
                       full ? "the sender's radio queue is full" : radio::error_name(r.error));
    }
    *result = {{"vehicle", *from}, {"seq", *r.seq}, {"time_s", sim_.time_s()}};
    return true;
  }
  if (op == "radio_subscribe" || op == "radio_unsubscribe") {
    // one vehicle, or every vehicle without "vehicle"
    std::set<size_t> which;
    if (vit != request.end()) {
      const auto v = vehicle(*vit, code, message);
      if (!v) return false;
      which.insert(*v);
    } else {
      for (size_t i = 0; i < sim_.vehicle_count(); ++i) which.insert(i);
    }
    std::optional<bool> batch;
    if (auto it = request.find("batch"); it != request.end()) {
      if (op != "radio_subscribe" || !it->is_boolean()) {
        return set_error(code, message, "bad_field",
                         "\"batch\" is a boolean of radio_subscribe (one radio_batch event a gate)");
      }
      batch = it->get<bool>();
    }
    Subscription& sub = subscriptions_[conn];
    if (batch) sub.batch = *batch;  // the connection's delivery form, for all its vehicles
    for (size_t v : which) {
      if (op == "radio_subscribe") {
        sub.vehicles.insert(v);
      } else {
        sub.vehicles.erase(v);
      }
    }
    *result = {{"vehicles", Json(std::vector<size_t>(sub.vehicles.begin(), sub.vehicles.end()))},
               {"batch", sub.batch},
               {"max_frame_bytes", radio_.model().max_payload_bytes()},
               {"time_s", sim_.time_s()}};
    return true;
  }
  if (op == "radio_stats") {
    std::optional<size_t> only;
    if (vit != request.end()) {
      only = vehicle(*vit, code, message);
      if (!only) return false;
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
    *result = {{"time_s", sim_.time_s()},
               {"backend", m.backend_name()},
               {"max_frame_bytes", m.max_payload_bytes()},
               {"failure", m.failure()},
               {"vehicles", vehicles},
               {"links", links},
               {"inbox_overflows", radio_.inbox_overflows()}};
    return true;
  }
  if (op == "radio_config") {
    if (!apply_config(request, code, message)) return false;
    *result = config_json();
    return true;
  }

  // the ground-station link relay
  if (relays_ == nullptr)
    return set_error(code, message, "not_available", "this server has no GCS link relay");
  if (vit == request.end())
    return set_error(code, message, "missing_field", "\"vehicle\" (index or name) is required");
  const auto v = vehicle(*vit, code, message);
  if (!v) return false;
  auto port_field = [&](const char* key, std::optional<uint16_t>* out) {
    auto it = request.find(key);
    if (it == request.end()) return true;
    if (!it->is_number_unsigned() || it->get<uint64_t>() > 65535) {
      return set_error(code, message, "bad_field",
                       std::string("\"") + key + "\" must be a port in [0, 65535]");
    }
    *out = static_cast<uint16_t>(it->get<uint64_t>());
    return true;
  };
  auto relay_json = [&](radio::GcsRelay& r) {
    const radio::RelayImpairment& i = r.impairment();
    const radio::RelayStats& s = r.stats();
    return Json{{"vehicle", *v},
                {"uav_port", r.uav_port()},
                {"gcs_port", r.gcs_port()},
                {"loss", i.loss_probability},
                {"latency_s", i.latency_s},
                {"outage_until_s",
                 std::isfinite(i.outage_until_s) ? Json(i.outage_until_s) : Json(nullptr)},
                {"to_gcs_forwarded", s.to_gcs_forwarded},
                {"to_gcs_dropped", s.to_gcs_dropped},
                {"to_uav_forwarded", s.to_uav_forwarded},
                {"to_uav_dropped", s.to_uav_dropped},
                {"time_s", sim_.time_s()}};
  };
  if (op == "gcs_link_open") {
    std::optional<uint16_t> uav_port, gcs_port, target_port;
    if (!port_field("uav_port", &uav_port) || !port_field("gcs_port", &gcs_port) ||
        !port_field("gcs_target_port", &target_port)) {
      return false;
    }
    std::optional<std::string> target_host;
    if (auto it = request.find("gcs_target_host"); it != request.end()) {
      if (!it->is_string())
        return set_error(code, message, "bad_field", "\"gcs_target_host\" must be an IPv4 address");
      target_host = it->get<std::string>();
    }
    std::string why;
    radio::GcsRelay* r = relays_->open(*v, uav_port.value_or(0), gcs_port.value_or(0), target_host,
                                       target_port, &why);
    if (r == nullptr) return set_error(code, message, "io_error", why);
    *result = relay_json(*r);
    return true;
  }
  radio::GcsRelay* r = relays_->relay(*v);
  if (r == nullptr) {
    return set_error(code, message, "not_available",
                     "vehicle " + std::to_string(*v) + " has no relay (gcs_link_open)");
  }
  if (op == "gcs_link_impair") {
    auto num = [&](const char* key, double fallback, double lo, double hi, double* out) {
      auto it = request.find(key);
      if (it == request.end()) {
        *out = fallback;
        return true;
      }
      if (!it->is_number() || !(it->get<double>() >= lo && it->get<double>() <= hi)) {
        return set_error(code, message, "bad_field",
                         std::string("\"") + key + "\" must be a number in [" + std::to_string(lo) +
                             ", " + std::to_string(hi) + "]");
      }
      *out = it->get<double>();
      return true;
    };
    double loss = 0.0, latency = 0.0, outage = 0.0;
    if (!num("loss", r->impairment().loss_probability, 0.0, 1.0, &loss) ||
        !num("latency_s", r->impairment().latency_s, 0.0, 3600.0, &latency) ||
        !num("outage_s", 0.0, 0.0, 1e6, &outage)) {
      return false;
    }
    r->impair(loss, latency, outage, sim_.time_s());
  }
  *result = relay_json(*r);
  return true;
}

void RadioOps::on_gate(const Send& send, const InLockstep& in_lockstep) {
  // frames that arrived by now go out before this gate announces its ticks (a lockstep batch
  // subscriber's just before its own tick); frames sent at this time go on air at the step, once
  // every lockstep client has sent its own (deterministic draws)
  radio_.advance(false);
  std::vector<radio::Delivery> arrived = radio_.take_deliveries();
  if (!arrived.empty() && !subscriptions_.empty()) queue_deliveries(arrived, send);
  // what is held for a connection that has left lockstep (or never joined) goes now
  for (auto it = held_.begin(); it != held_.end();) {
    const uint64_t conn = (it++)->first;
    if (!in_lockstep(conn)) send_held(conn, send);
  }
}

void RadioOps::before_tick(uint64_t conn, const Send& send) { send_held(conn, send); }

void RadioOps::send_held(uint64_t conn, const Send& send) {
  const auto it = held_.find(conn);
  if (it == held_.end()) return;
  Json frames = std::move(it->second);
  held_.erase(it);
  send(conn, Json{{"event", "radio_batch"}, {"time", sim_.time_s()}, {"frames", std::move(frames)}});
}

void RadioOps::queue_deliveries(const std::vector<radio::Delivery>& arrived, const Send& send) {
  // a broadcast is one delivery per receiver with the same bytes: encoded once per frame
  std::map<std::pair<size_t, uint64_t>, std::string> encoded;  // (from, seq) -> base64
  auto data_b64 = [&](const radio::Delivery& d) -> const std::string& {
    auto [it, fresh] = encoded.try_emplace({d.from, d.seq});
    if (fresh) it->second = common::base64_encode(d.data);
    return it->second;
  };
  for (const radio::Delivery& d : arrived) {
    Json event;  // built once, for the first subscriber that hears it
    Json compact;
    for (const auto& [conn, sub] : subscriptions_) {
      if (sub.vehicles.count(d.to) == 0) continue;
      if (sub.batch) {
        // [to, from, seq, broadcast, time, sent_time, data_b64]: the event's fields, keys once
        if (compact.is_null()) {
          compact = Json::array(
              {d.to, d.from, d.seq, d.broadcast, d.time_s, d.queued_s, data_b64(d)});
        }
        Json& batch = held_[conn];
        if (batch.is_null()) batch = Json::array();
        batch.push_back(compact);
        continue;
      }
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
    }
  }
}

void RadioOps::on_disconnect(uint64_t conn) {
  subscriptions_.erase(conn);
  held_.erase(conn);
}

}  // namespace uavsim::server::api
