#include "api/op_table.hpp"

#include <stdexcept>

namespace uavsim::server::api {

nlohmann::json ok_reply(const nlohmann::json& id, nlohmann::json result) {
  return nlohmann::json{{"id", id}, {"ok", true}, {"result", std::move(result)}};
}

nlohmann::json error_reply(const nlohmann::json& id, ApiError code, const std::string& message) {
  return nlohmann::json{{"id", id},
                        {"ok", false},
                        {"error", {{"code", common::api_error_code(code)}, {"message", message}}}};
}

void OpTable::add(OpSpec spec) {
  if (const OpSpec* earlier = find(spec.name)) {
    throw std::logic_error("sim API op '" + spec.name + "' registered twice (groups '" +
                           earlier->group + "' and '" + spec.group + "')");
  }
  index_.emplace(spec.name, ops_.size());
  ops_.push_back(std::move(spec));
}

const OpSpec* OpTable::find(std::string_view name) const {
  auto it = index_.find(name);
  return it == index_.end() ? nullptr : &ops_[it->second];
}

std::vector<std::string> OpTable::names() const {
  std::vector<std::string> names;
  names.reserve(ops_.size());
  for (const OpSpec& op : ops_) names.push_back(op.name);
  return names;
}

}  // namespace uavsim::server::api
