// The option parser: every bad value is refused with a message naming the option and what it needs;
// keys and tokens come from files or the environment; --out expands per vehicle.
#include <gtest/gtest.h>

#include <fstream>
#include <map>

#include "app/options.hpp"
#include "app/server_app.hpp"

namespace uavsim::server::app {
namespace {

const std::string kKeyHex = "00112233445566778899aabbccddeeff00112233445566778899AABBCCDDEEFF";

ParseResult parse(std::vector<std::string> args, std::map<std::string, std::string> env = {}) {
  return parse_args(args, [env](const std::string& name) -> std::optional<std::string> {
    auto it = env.find(name);
    if (it == env.end()) return std::nullopt;
    return it->second;
  });
}

// the parse fails with exit code 2 and a message holding every fragment
void expect_refused(std::vector<std::string> args, std::vector<std::string> fragments) {
  const ParseResult r = parse(args);
  EXPECT_FALSE(r.options.has_value()) << args.back();
  EXPECT_EQ(r.exit_code, 2);
  for (const std::string& f : fragments) EXPECT_NE(r.error.find(f), std::string::npos) << r.error;
}

std::string write_file(const std::string& name, const std::string& text) {
  const std::string path = ::testing::TempDir() + name;
  std::ofstream(path) << text;
  return path;
}

TEST(Options, DefaultsAreSitlLike) {
  const ParseResult r = parse({"w.xml"});
  ASSERT_TRUE(r.options);
  EXPECT_EQ(r.options->mavlink_base_port, 5760);
  EXPECT_EQ(r.options->api_port, 5700);
  EXPECT_EQ(r.options->bind_address, "127.0.0.1");
  EXPECT_FALSE(r.options->udp_outs_explicit);
  EXPECT_FALSE(r.options->mavlink_key);
  EXPECT_EQ(r.options->wait_for_clients, 0);
}

TEST(Options, OutOfRangeNumbersSayWhatTheOptionNeeds) {
  expect_refused({"w.xml", "--rate", "-1"}, {"--rate", "-1", "from 0"});
  expect_refused({"w.xml", "--mavlink-port", "99999"}, {"--mavlink-port", "99999", "65535"});
  expect_refused({"w.xml", "--api-port", "-2"}, {"--api-port", "-2"});
  expect_refused({"w.xml", "--mavlink-port", "5760.5"}, {"--mavlink-port", "5760.5"});
  expect_refused({"w.xml", "--seed", "x"}, {"--seed", "'x'"});
  expect_refused({"w.xml", "--physics-hz", "0"}, {"--physics-hz"});
  expect_refused({"w.xml", "--duration", "nan"}, {"--duration"});
  expect_refused({"w.xml", "--wait-for-clients", "-3"}, {"--wait-for-clients"});
  expect_refused({"w.xml", "--record-size", "640x"}, {"--record-size"});
  expect_refused({"w.xml", "--record-layout", "mosaic"}, {"--record-layout", "single or tiled"});
  expect_refused({"w.xml", "--rate"}, {"--rate needs a value"});
  expect_refused({"w.xml", "--bogus"}, {"unknown option --bogus"});
  expect_refused({}, {"no world given"});
  expect_refused({"a.xml", "b.xml"}, {"more than one world"});
}

TEST(Options, VersionAndHelpExitZeroWithText) {
  ParseResult r = parse({"--version"});
  EXPECT_FALSE(r.options);
  EXPECT_EQ(r.exit_code, 0);
  EXPECT_EQ(r.output.rfind("uavsim-server ", 0), 0u) << r.output;
  r = parse({"--help"});
  EXPECT_EQ(r.exit_code, 0);
  EXPECT_NE(r.output.find("--out URL"), std::string::npos);
}

TEST(Options, HomeIsRangeChecked) {
  ParseResult r = parse({"w.xml", "--home", "-35.363261,149.165230,584,0"});
  ASSERT_TRUE(r.options && r.options->home);
  EXPECT_DOUBLE_EQ(r.options->home->lat_deg, -35.363261);
  EXPECT_DOUBLE_EQ(r.options->home->alt_m, 584.0);
  expect_refused({"w.xml", "--home", "-35.363261,149.165230,584,90"}, {"--home", "yaw_deg"});
  r = parse({"w.xml", "--home", "1,2,3"});
  ASSERT_TRUE(r.options && r.options->home);
  EXPECT_DOUBLE_EQ(r.options->home->heading_deg, 0.0);
  expect_refused({"w.xml", "--home", "91,0,0"}, {"--home", "latitude"});
  expect_refused({"w.xml", "--home", "1,2"}, {"--home"});
  expect_refused({"w.xml", "--home", "1,2,3,4,5"}, {"--home"});
}

TEST(Options, SigningKeyFromOptionFileOrEnvironment) {
  ParseResult r = parse({"w.xml", "--mavlink-key", kKeyHex});
  ASSERT_TRUE(r.options && r.options->mavlink_key);
  EXPECT_EQ((*r.options->mavlink_key)[1], 0x11);
  EXPECT_EQ((*r.options->mavlink_key)[31], 0xff);
  const std::string file = write_file("key.txt", "  " + kKeyHex + "\n");
  r = parse({"w.xml", "--mavlink-key-file", file});
  ASSERT_TRUE(r.options && r.options->mavlink_key);
  EXPECT_EQ((*r.options->mavlink_key)[0], 0x00);
  EXPECT_EQ((*r.options->mavlink_key)[2], 0x22);
  r = parse({"w.xml"}, {{"UAVSIM_MAVLINK_KEY", kKeyHex}});
  ASSERT_TRUE(r.options && r.options->mavlink_key);
  // an option wins over the environment
  r = parse({"w.xml", "--mavlink-key", std::string(64, '0')}, {{"UAVSIM_MAVLINK_KEY", kKeyHex}});
  ASSERT_TRUE(r.options && r.options->mavlink_key);
  EXPECT_EQ((*r.options->mavlink_key)[1], 0x00);
  const ParseResult bad = parse({"w.xml"}, {{"UAVSIM_MAVLINK_KEY", "abc"}});
  EXPECT_FALSE(bad.options);
  EXPECT_NE(bad.error.find("UAVSIM_MAVLINK_KEY"), std::string::npos) << bad.error;
  expect_refused({"w.xml", "--mavlink-key-file", ::testing::TempDir() + "missing"}, {"cannot read"});
  expect_refused({"w.xml", "--mavlink-key", kKeyHex.substr(2) + "zz"}, {"64 hex digits"});
}

TEST(Options, ApiTokenFromFile) {
  const std::string file = write_file("token.txt", "s3cret token\nsecond line\n");
  const ParseResult r = parse({"w.xml", "--api-token-file", file, "--allow-remote-gcs"});
  ASSERT_TRUE(r.options && r.options->api_token);
  EXPECT_EQ(*r.options->api_token, "s3cret token");
  EXPECT_TRUE(r.options->allow_remote_gcs);
  expect_refused({"w.xml", "--api-token-file", write_file("empty.txt", "\n")}, {"empty"});
}

TEST(Options, UdpOutExpandsPerVehicle) {
  const ParseResult r = parse({"w.xml", "--out", "udp:127.0.0.1:14550", "--out", "2=udpin:0.0.0.0:14600",
                               "--out", "udp:10.0.0.{i}:14550"});
  ASSERT_TRUE(r.options);
  ASSERT_EQ(r.options->udp_outs.size(), 3u);
  std::string why;
  // base + 10 i
  auto t = udp_target(r.options->udp_outs[0], 3, &why);
  ASSERT_TRUE(t);
  EXPECT_EQ(t->url(), "udp:127.0.0.1:14580");
  // one vehicle only, port as given
  EXPECT_FALSE(udp_target(r.options->udp_outs[1], 0, &why));
  EXPECT_TRUE(why.empty());
  t = udp_target(r.options->udp_outs[1], 2, &why);
  ASSERT_TRUE(t);
  EXPECT_EQ(t->url(), "udpin:0.0.0.0:14600");
  // {i} in place of the offset
  t = udp_target(r.options->udp_outs[2], 7, &why);
  ASSERT_TRUE(t);
  EXPECT_EQ(t->url(), "udp:10.0.0.7:14550");
  // past 65535 for a high vehicle index
  EXPECT_FALSE(udp_target(UdpOut{"udp:127.0.0.1:65530", std::nullopt}, 1, &why));
  EXPECT_NE(why.find("65540"), std::string::npos) << why;

  const ParseResult none = parse({"w.xml", "--out", "none"});
  ASSERT_TRUE(none.options);
  EXPECT_TRUE(none.options->udp_outs_explicit);
  EXPECT_TRUE(none.options->udp_outs.empty());
  expect_refused({"w.xml", "--out", "tcp:1.2.3.4:5"}, {"--out", "udp:HOST:PORT"});
  expect_refused({"w.xml", "--out", "udp:127.0.0.1:0"}, {"--out", "port"});
  expect_refused({"w.xml", "--out", "x=udp:127.0.0.1:1"}, {"vehicle index"});
}

TEST(Options, PortRangeForTheWorldsVehicleCount) {
  EXPECT_FALSE(port_range_error("--mavlink-port", 5760, 100));
  EXPECT_FALSE(port_range_error("--mavlink-port", 0, 100000));
  const auto why = port_range_error("--mavlink-port", 65000, 100);
  ASSERT_TRUE(why);
  // vehicle 99: 65000 + 990 = 65990; the highest base for 100 vehicles: 65535 - 990 = 64545
  EXPECT_NE(why->find("65990"), std::string::npos) << *why;
  EXPECT_NE(why->find("64545"), std::string::npos) << *why;
  EXPECT_NE(why->find("--mavlink-port 0"), std::string::npos) << *why;
}

TEST(Options, NonLoopbackBindsAreWarnedAbout) {
  ParseResult r = parse({"w.xml"});
  EXPECT_TRUE(option_warnings(*r.options).empty());
  r = parse({"w.xml", "--bind", "0.0.0.0", "--api-bind", "192.168.1.2"});
  const auto w = option_warnings(*r.options);
  ASSERT_EQ(w.size(), 2u);
  EXPECT_NE(w[0].find("--bind 0.0.0.0"), std::string::npos) << w[0];
  EXPECT_NE(w[1].find("no authentication"), std::string::npos) << w[1];
  r = parse({"w.xml", "--api-bind", "0.0.0.0", "--api-port", "-1"});
  EXPECT_TRUE(option_warnings(*r.options).empty());
}

TEST(Options, UnknownWorldListsTheShippedOnes) {
  EXPECT_EQ(resolve_world_path("mbzirc2020", UAVSIM_MODELS_DIR),
            std::string(UAVSIM_MODELS_DIR) + "/worlds/mbzirc2020.xml");
  EXPECT_EQ(resolve_world_path("empty.xml", UAVSIM_MODELS_DIR), std::string(UAVSIM_MODELS_DIR) + "/worlds/empty.xml");
  try {
    resolve_world_path("no_such_world", UAVSIM_MODELS_DIR);
    FAIL() << "no error";
  } catch (const std::runtime_error& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("no_such_world"), std::string::npos) << what;
    for (const char* w : {"empty", "grid100", "hexa", "mbzirc2017", "mbzirc2020"}) {
      EXPECT_NE(what.find(w), std::string::npos) << what;
    }
  }
}

}  // namespace
}  // namespace uavsim::server::app
