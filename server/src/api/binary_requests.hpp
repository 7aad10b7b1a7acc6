// A request ring's binary requests (docs/protocol.md, "Shared-memory stream"; the records:
// common/shm_requests.hpp) as the JSON requests they stand for, so that the API serves them as it
// serves a line: radio_send with its frame as a binary value under "data" (no base64; a text
// request cannot carry one), done with its fields; "id" "b<tag>" unless the tag is 0.
#pragma once

#include <cstdint>
#include <nlohmann/json.hpp>
#include <optional>
#include <span>
#include <string>

namespace uavsim::server::api {

// The request of a kRadioSend or kDone record; nullopt with *why if the payload is out of range or
// the type is neither.
std::optional<nlohmann::json> binary_request_json(std::uint16_t type,
                                                  std::span<const std::uint8_t> payload,
                                                  std::string* why);

}  // namespace uavsim::server::api
