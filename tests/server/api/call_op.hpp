// Serves one request to an op group as the API server does, without a socket: the op's declared
// fields are checked first (a mistyped one never reaches the handler), then its handler runs.
#pragma once

#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>

#include "api/op_table.hpp"
#include "api/request_fields.hpp"
#include "uavsim/common/api_error.hpp"

namespace uavsim::server::api::testing {

// The op's result, or {"error": code} (code as on the wire).
inline nlohmann::json call_op(OpGroup& group, const std::string& op, const nlohmann::json& request,
                              uint64_t conn = 1) {
  OpTable table;
  group.register_ops(table);
  const OpSpec* spec = table.find(op);
  if (spec == nullptr) return {{"error", "unknown_op"}};
  if (mistyped_field(request, spec->typed_fields)) return {{"error", "bad_field"}};
  OpReply reply;
  spec->handler(conn, request, &reply);
  if (reply.failed()) return {{"error", std::string(common::api_error_code(*reply.error))}};
  return reply.result;
}

}  // namespace uavsim::server::api::testing
