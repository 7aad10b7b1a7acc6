#include "api/binary_requests.hpp"

#include <utility>

#include "uavsim/common/shm_requests.hpp"
#include "uavsim/common/shm_ring.hpp"

namespace uavsim::server::api {

namespace {

using Json = nlohmann::json;
namespace shm = common::shm;

std::optional<Json> radio_send_json(std::span<const std::uint8_t> payload, std::string* why) {
  auto r = shm::decode_radio_send(payload, why);
  if (!r) return std::nullopt;
  Json body = {
      {"op", "radio_send"}, {"vehicle", r->vehicle}, {"data", Json::binary(std::move(r->data))}};
  if (r->to < 0) {
    body["to"] = "broadcast";
  } else {
    body["to"] = r->to;
  }
  if (r->tag != 0) body["id"] = std::string("b").append(std::to_string(r->tag));
  return body;
}

std::optional<Json> done_json(std::span<const std::uint8_t> payload, std::string* why) {
  auto d = shm::decode_done(payload, why);
  if (!d) return std::nullopt;
  Json body = {{"op", "done"}, {"quiet", d->quiet}};
  if (d->tick) body["tick"] = *d->tick;
  if (d->busy_until_s) body["busy_until"] = *d->busy_until_s;
  if (!d->mavlink_seq.empty()) {
    Json seqs = Json::object();
    for (const auto& [vehicle, seq] : d->mavlink_seq) seqs[std::to_string(vehicle)] = seq;
    body["mavlink_seq"] = std::move(seqs);
  }
  if (d->tag != 0) body["id"] = std::string("b").append(std::to_string(d->tag));
  return body;
}

}  // namespace

std::optional<Json> binary_request_json(std::uint16_t type, std::span<const std::uint8_t> payload,
                                        std::string* why) {
  if (type == static_cast<std::uint16_t>(shm::RecordType::kRadioSend))
    return radio_send_json(payload, why);
  if (type == static_cast<std::uint16_t>(shm::RecordType::kDone)) return done_json(payload, why);
  *why = "a binary request of type " + std::to_string(type);
  return std::nullopt;
}

}  // namespace uavsim::server::api
