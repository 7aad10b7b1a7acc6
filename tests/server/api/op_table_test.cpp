// The op table: one registry for every op group's ops, its duplicate check, and docs/protocol.md
// documenting every op a fully equipped server serves.
#include "api/op_table.hpp"

#include <gtest/gtest.h>

#include <fstream>
#include <memory>
#include <set>
#include <sstream>
#include <stdexcept>
#include <string>

#include "api/api_server.hpp"
#include "api/overlay_ops.hpp"
#include "api/radio_ops.hpp"
#include "api/sensor_ops.hpp"
#include "objects/world_objects.hpp"
#include "physics/world.hpp"
#include "radio/gcs_relay.hpp"
#include "radio/sim_radio.hpp"
#include "uavsim/common/api_error.hpp"

namespace uavsim::server::api {
namespace {

using Json = nlohmann::json;

void answer_ok(uint64_t, const Json&, OpReply*) {}

TEST(OpTable, ListsOpsInRegistrationOrderAndFindsThemByName) {
  OpTable table;
  table.add({"b", "g1", answer_ok});
  table.add({"a", "g2", answer_ok});
  EXPECT_EQ(table.names(), (std::vector<std::string>{"b", "a"}));
  ASSERT_NE(table.find("a"), nullptr);
  EXPECT_EQ(table.find("a")->group, "g2");
  EXPECT_EQ(table.find("c"), nullptr);
}

TEST(OpTable, AnOpRegisteredTwiceIsAStartupErrorNamingBothGroups) {
  OpTable table;
  table.add({"status", "clock", answer_ok});
  try {
    table.add({"status", "radio", answer_ok});
    FAIL() << "a duplicate op was accepted";
  } catch (const std::logic_error& e) {
    EXPECT_NE(std::string(e.what()).find("'status'"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("'radio'"), std::string::npos) << e.what();
  }
}

// a group whose handlers take what they need of (conn, request, reply)
struct ThreeShapes {
  void with_conn(uint64_t conn, const Json& request, OpReply* reply) {
    reply->result = {{"conn", conn}, {"x", request["x"]}};
  }
  void with_request(const Json& request, OpReply* reply) const { reply->result = request["x"]; }
  void reply_only(OpReply* reply) const { reply->result = "listed"; }
};

TEST(OpRegistrar, RegistersMembersOfEveryShapeUnderTheGroupsNameAndFields) {
  static constexpr FieldSpec kOwn[] = {{"x", FieldType::kNumber}};
  OpTable table;
  ThreeShapes group;
  const OpRegistrar<ThreeShapes> add(table, &group, "shapes");
  add("a", &ThreeShapes::with_conn);
  add("b", &ThreeShapes::with_request, kOwn);
  add("c", &ThreeShapes::reply_only, {});
  EXPECT_EQ(table.names(), (std::vector<std::string>{"a", "b", "c"}));
  for (const char* op : {"a", "b", "c"}) EXPECT_EQ(table.find(op)->group, "shapes") << op;
  // the core fields unless the op names its own
  EXPECT_EQ(table.find("a")->typed_fields.size(), core_op_fields().size());
  EXPECT_EQ(table.find("b")->typed_fields.size(), 1u);
  EXPECT_TRUE(table.find("c")->typed_fields.empty());
  // each handler is handed what it takes
  OpReply reply;
  table.find("a")->handler(7, {{"x", 2}}, &reply);
  EXPECT_EQ(reply.result, (Json{{"conn", 7}, {"x", 2}}));
  table.find("b")->handler(7, {{"x", 3}}, &reply);
  EXPECT_EQ(reply.result, 3);
  table.find("c")->handler(7, Json::object(), &reply);
  EXPECT_EQ(reply.result, "listed");
}

TEST(ApiErrorCodes, EveryCodeHasItsOwnWireNameThatReadsBack) {
  std::set<std::string_view> names;
  for (const auto& [code, name] : common::kApiErrorCodes) {
    EXPECT_TRUE(names.insert(name).second) << name << " named twice";
    EXPECT_EQ(common::api_error_code(code), name);
    EXPECT_EQ(common::api_error_from_code(name), code) << name;
  }
  EXPECT_EQ(common::api_error_from_code("no_such_code"), std::nullopt);
}

// every op of the radio, sensor and overlay groups that reads a field declares it: a mistyped field
// is refused before the op runs, as for the server's own ops
TEST(OpTable, RadioSensorAndOverlayOpsDeclareTheirFields) {
  physics::ComposeOptions o;
  o.models_dir = UAVSIM_MODELS_DIR;
  sim::Simulation sim(physics::World::load(std::string(UAVSIM_MODELS_DIR) + "/worlds/empty.xml", o),
                      sim::SimConfig{});
  RadioOps radio(sim, radio::SimRadio::attach(sim, radio::RadioConfig{}),
                 &radio::GcsRelaySet::attach(sim, "127.0.0.1"));
  SensorOps sensors(sim);
  OverlayOps overlay(sim);
  OpTable table;
  radio.register_ops(table);
  sensors.register_ops(table);
  overlay.register_ops(table);
  EXPECT_EQ(table.names().size(), 14u);
  for (const std::string& op : table.names()) {
    if (op == "sensor_list") continue;  // reads no field
    const OpSpec* spec = table.find(op);
    ASSERT_NE(spec, nullptr);
    EXPECT_FALSE(spec->typed_fields.empty()) << op;
  }
  // radio_send's sender is an index or a name: a number of another kind is refused by the table's
  // spec
  Json bad = {{"op", "radio_send"}, {"vehicle", 0.5}, {"to", "broadcast"}, {"data_b64", "AA=="}};
  EXPECT_TRUE(mistyped_field(bad, table.find("radio_send")->typed_fields).has_value());
}

// every op of a server with every group (camera ops answer not_available without frames, but are
// served) appears in docs/protocol.md as `name`
TEST(OpTable, EveryOpServedIsDocumentedInTheProtocol) {
  physics::ComposeOptions o;
  o.models_dir = UAVSIM_MODELS_DIR;
  sim::Simulation sim(physics::World::load(std::string(UAVSIM_MODELS_DIR) + "/worlds/empty.xml", o),
                      sim::SimConfig{});
  const objects::ObjectSet objects = objects::add_world_objects(sim);
  RadioOps radio(sim, radio::SimRadio::attach(sim, radio::RadioConfig{}),
                 &radio::GcsRelaySet::attach(sim, "127.0.0.1"));
  SensorOps sensors(sim);
  OverlayOps overlay(sim);
  ApiConfig config;
  config.port = 0;
  ApiServer server(sim, nullptr, objects, config);
  server.add_group(&radio);
  server.add_group(&sensors);
  server.add_group(&overlay);
  server.start();
  const std::vector<std::string> ops = server.op_names();
  server.shutdown();

  std::ifstream in(std::string(UAVSIM_TEST_DATA_DIR) + "/../../docs/protocol.md");
  ASSERT_TRUE(in) << "docs/protocol.md not found";
  std::stringstream text;
  text << in.rdbuf();
  EXPECT_GE(ops.size(), 40u);  // the groups registered (a broken registry would pass vacuously)
  for (const std::string& op : ops) {
    EXPECT_NE(text.str().find("`" + op + "`"), std::string::npos)
        << "op '" << op << "' is not documented";
  }
}

}  // namespace
}  // namespace uavsim::server::api
