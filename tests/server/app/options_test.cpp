// The option parser: every bad value is refused with a message naming the option and what it needs;
// keys and tokens come from files or the environment; --out expands per vehicle.
#include "app/options.hpp"

#include <gtest/gtest.h>

#include <fstream>
#include <map>

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

TEST(Options, PhysicsShardsTakeACountOrAuto) {
  EXPECT_EQ(parse({"w.xml"}).options->physics_shards, 1);
  EXPECT_EQ(parse({"w.xml"}).options->physics_threads, 0);
  EXPECT_EQ(parse({"w.xml", "--physics-shards", "auto"}).options->physics_shards, 0);
  const ParseResult r = parse({"w.xml", "--physics-shards", "4", "--physics-threads", "2"});
  ASSERT_TRUE(r.options) << r.error;
  EXPECT_EQ(r.options->physics_shards, 4);
  EXPECT_EQ(r.options->physics_threads, 2);
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
  EXPECT_EQ(r.options->gl_backend, "osmesa");
  EXPECT_EQ(r.options->render_threads, 0);
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
  expect_refused({"w.xml", "--gl", "vulkan"}, {"--gl", "egl, osmesa or auto", "'vulkan'"});
  expect_refused({"w.xml", "--render-threads", "0"}, {"--render-threads", "from 1 to 64"});
  expect_refused({"w.xml", "--render-threads", "65"}, {"--render-threads", "'65'"});
  expect_refused({"w.xml", "--physics-shards", "0"}, {"--physics-shards", "from 1 to 64"});
  expect_refused({"w.xml", "--physics-shards", "many"}, {"--physics-shards", "'many'"});
  expect_refused({"w.xml", "--physics-shards"}, {"--physics-shards", "needs a value"});
  expect_refused({"w.xml", "--physics-threads", "65"}, {"--physics-threads", "'65'"});
  expect_refused({"w.xml", "--rate"}, {"--rate needs a value"});
  expect_refused({"w.xml", "--bogus"}, {"unknown option --bogus"});
  expect_refused({}, {"no world given"});
  expect_refused({"a.xml", "b.xml"}, {"more than one world"});
}

TEST(Options, RecordTilesNameACameraAndOneOfItsImages) {
  const ParseResult r =
      parse({"w.xml", "--record-tile", "uav0_front:depth", "--record-tile", "uav1_front"});
  ASSERT_TRUE(r.options.has_value()) << r.error;
  EXPECT_EQ(r.options->record_tiles, (std::vector<std::string>{"uav0_front:depth", "uav1_front"}));
  EXPECT_TRUE(r.options->record_tiled);
  expect_refused({"w.xml", "--record-tile", "uav0_front:thermal"},
                 {"--record-tile", "rgb|depth|segmentation"});
  expect_refused({"w.xml", "--record-tile", ":depth"}, {"--record-tile"});
  std::vector<std::string> many{"w.xml"};
  for (int i = 0; i < 7; ++i) many.insert(many.end(), {"--record-tile", "c" + std::to_string(i)});
  expect_refused(many, {"--record-tile", "at most 6"});
}

// --render-cameras: names, formats and rates are shaped and range-checked here; whether the world
// has the camera, and whether the rate divides the camera's, the server checks (server_cli_test)
TEST(Options, RenderCamerasAreShapedAndRangeChecked) {
  const ParseResult r = parse({"w.xml", "--render-cameras", "uav0_front@15,uav1_front:grey",
                               "--render-cameras", "down:depth@7.5"});
  ASSERT_TRUE(r.options.has_value()) << r.error;
  const std::vector<RenderCamera>& c = r.options->render_cameras;
  ASSERT_EQ(c.size(), 3u);
  EXPECT_EQ(c[0].camera, "uav0_front");
  EXPECT_EQ(c[0].format, "rgb");
  EXPECT_EQ(c[0].fps_hz, 15.0);
  EXPECT_EQ(c[1].camera, "uav1_front");
  EXPECT_EQ(c[1].format, "grey");
  EXPECT_FALSE(c[1].fps_hz.has_value());  // the camera's own rate
  EXPECT_EQ(c[2].format, "depth");
  EXPECT_EQ(c[2].fps_hz, 7.5);
  EXPECT_TRUE(parse({"w.xml"}).options->render_cameras.empty());
  for (const char* fps : {"0", "-1", "1000.5", "nan", "inf", "1e308", "", "15x"}) {
    expect_refused({"w.xml", "--render-cameras", std::string("cam@") + fps},
                   {"--render-cameras", "FPS needs frames per sim second from 0.001 to 1000"});
  }
  for (const char* bad : {"", "cam:jpeg", ":rgb", "@15", "cam,", ",cam", "a,,b"}) {
    expect_refused({"w.xml", "--render-cameras", bad},
                   {"--render-cameras needs CAMERA[:rgb|grey|depth|segmentation][@FPS]"});
  }
  expect_refused({"w.xml", "--render-cameras", "cam,cam:grey"}, {"camera 'cam' named twice"});
  expect_refused({"w.xml", "--render-cameras", "cam", "--render-cameras", "cam@1"},
                 {"camera 'cam' named twice"});
  expect_refused({"w.xml", "--render-cameras", "cam", "--no-cameras"},
                 {"--render-cameras needs the renderer"});
  expect_refused({"w.xml", "--render-cameras"}, {"--render-cameras needs a value"});
}

TEST(Options, ValidFlagsSetTheirFields) {
  const ParseResult r = parse({"w.xml",
                               "--seed",
                               "42",
                               "--physics-hz",
                               "2000",
                               "--control-hz",
                               "400",
                               "--rate",
                               "2.5",
                               "--duration",
                               "90",
                               "--wait-for-clients",
                               "3",
                               "--realism",
                               "field",
                               "--wind",
                               "6,270,1.5",
                               "--mavlink-port",
                               "-1",
                               "--api-port",
                               "0",
                               "--lockstep-timeout",
                               "0.5",
                               "--record",
                               "o.mp4",
                               "--record-fps",
                               "30",
                               "--record-size",
                               "1280x720",
                               "--record-overlay",
                               "0",
                               "--record-layout",
                               "tiled",
                               "--record-camera",
                               "follow:uav1",
                               "--no-cameras",
                               "--gl",
                               "auto",
                               "--render-threads",
                               "3",
                               "--quiet"});
  ASSERT_TRUE(r.options) << r.error;
  const Options& o = *r.options;
  EXPECT_EQ(o.world_path, "w.xml");
  EXPECT_EQ(o.seed, 42u);
  EXPECT_EQ(o.physics_hz, 2000.0);
  EXPECT_EQ(o.control_hz, 400.0);
  EXPECT_EQ(o.rate, 2.5);
  EXPECT_EQ(o.duration_s, 90.0);
  EXPECT_EQ(o.wait_for_clients, 3);
  EXPECT_EQ(o.realism, "field");
  ASSERT_TRUE(o.wind);
  EXPECT_EQ(o.wind->speed_m_s, 6.0);
  EXPECT_EQ(o.wind->from_deg, 270.0);
  EXPECT_EQ(o.wind->turbulence_sd_m_s, 1.5);
  EXPECT_EQ(o.mavlink_base_port, -1);
  EXPECT_EQ(o.api_port, 0);
  EXPECT_EQ(o.lockstep_timeout_s, 0.5);
  EXPECT_EQ(o.record_path, "o.mp4");
  EXPECT_EQ(o.record_fps, 30.0);
  EXPECT_EQ(o.record_width, 1280);
  EXPECT_EQ(o.record_height, 720);
  EXPECT_FALSE(o.record_overlay);
  EXPECT_TRUE(o.record_tiled);
  EXPECT_EQ(o.record_camera, "follow:uav1");
  EXPECT_FALSE(o.cameras);
  EXPECT_EQ(o.gl_backend, "auto");
  EXPECT_EQ(o.render_threads, 3);
  EXPECT_TRUE(o.quiet);
  // --fast is --rate 0; a wind without gust leaves the turbulence to the realism level
  const ParseResult fast = parse({"w.xml", "--fast", "--wind", "3,90"});
  ASSERT_TRUE(fast.options) << fast.error;
  EXPECT_EQ(fast.options->rate, 0.0);
  EXPECT_FALSE(fast.options->wind->turbulence_sd_m_s);
}

TEST(Options, RangeEdgesAreInclusive) {
  auto accepted = [](std::vector<std::string> args) {
    const ParseResult r = parse(args);
    EXPECT_TRUE(r.options) << args[1] << " " << args[2] << ": " << r.error;
    return r.options ? *r.options : Options{};
  };
  EXPECT_EQ(accepted({"w.xml", "--mavlink-port", "-1"}).mavlink_base_port, -1);
  EXPECT_EQ(accepted({"w.xml", "--mavlink-port", "65535"}).mavlink_base_port, 65535);
  expect_refused({"w.xml", "--mavlink-port", "65536"},
                 {"--mavlink-port", "'65536'", "-1 to 65535"});
  expect_refused({"w.xml", "--api-port", "65536"}, {"--api-port", "'65536'"});
  // seeds: integers 0 .. 2^53 (exact in a double)
  EXPECT_EQ(accepted({"w.xml", "--seed", "0"}).seed, 0u);
  EXPECT_EQ(accepted({"w.xml", "--seed", "9007199254740992"}).seed, 9007199254740992u);
  expect_refused({"w.xml", "--seed", "18014398509481984"}, {"--seed", "an integer"});  // 2^54
  expect_refused({"w.xml", "--seed", "-1"}, {"--seed", "'-1'"});
  expect_refused({"w.xml", "--seed", "1.5"}, {"--seed", "'1.5'"});
  EXPECT_EQ(accepted({"w.xml", "--rate", "0"}).rate, 0.0);
  EXPECT_EQ(accepted({"w.xml", "--rate", "1000000"}).rate, 1e6);
  expect_refused({"w.xml", "--rate", "1000001"}, {"--rate", "from 0 to 1e+06"});
  EXPECT_EQ(accepted({"w.xml", "--wait-for-clients", "100000"}).wait_for_clients, 100000);
  expect_refused({"w.xml", "--wait-for-clients", "100001"}, {"--wait-for-clients"});
  expect_refused({"w.xml", "--physics-hz", "0.5"}, {"--physics-hz", "from 1 to 100000"});
  expect_refused({"w.xml", "--control-hz", "100001"}, {"--control-hz"});
  expect_refused({"w.xml", "--lockstep-timeout", "0"}, {"--lockstep-timeout", "wall seconds"});
  expect_refused({"w.xml", "--record-fps", "0"}, {"--record-fps", "frames per second"});
  expect_refused({"w.xml", "--duration", "-1"}, {"--duration", "seconds of sim time"});
}

TEST(Options, HugeNonFiniteAndMalformedNumbersAreRefusedByName) {
  // every numeric option refuses what is not a finite number in its range, quoting the text
  for (const char* flag :
       {"--seed", "--physics-hz", "--control-hz", "--rate", "--duration", "--wait-for-clients",
        "--mavlink-port", "--api-port", "--lockstep-timeout", "--record-fps"}) {
    for (const char* text :
         {"1e400", "-1e400", "nan", "inf", "-inf", "1e30", "", "12abc", "abc", " "}) {
      SCOPED_TRACE(std::string(flag) + " '" + text + "'");
      expect_refused({"w.xml", flag, text}, {flag, "needs", "got '" + std::string(text) + "'"});
    }
  }
}

TEST(Options, AnOptionAtTheEndWithoutItsValueIsNamed) {
  for (const char* flag : {"--seed",
                           "--physics-hz",
                           "--control-hz",
                           "--rate",
                           "--duration",
                           "--wait-for-clients",
                           "--home",
                           "--realism",
                           "--wind",
                           "--defaults",
                           "--write-world",
                           "--models-dir",
                           "--mavlink-port",
                           "--bind",
                           "--out",
                           "--mavlink-key",
                           "--mavlink-key-file",
                           "--api-port",
                           "--api-bind",
                           "--api-token-file",
                           "--lockstep-timeout",
                           "--camera",
                           "--record",
                           "--record-fps",
                           "--record-camera",
                           "--record-overlay",
                           "--record-layout",
                           "--record-size",
                           "--log-dir"}) {
    expect_refused({"w.xml", flag}, {std::string(flag) + " needs a value"});
  }
  // the next option is taken as the value, and refused as one
  expect_refused({"w.xml", "--rate", "--fast"}, {"--rate", "got '--fast'"});
}

TEST(Options, WindIsShapedAndRangeChecked) {
  // speed 0..50 m/s, direction -360..360 degrees, turbulence 0..20 m/s
  for (const char* ok : {"0,0", "50,360", "50,-360,20", "7.5,45,0"}) {
    EXPECT_TRUE(parse({"w.xml", "--wind", ok}).options) << ok;
  }
  for (const char* bad : {"51,0", "-1,0", "5,361", "5,-361", "5,0,21", "5,0,-1", "5", "5,0,1,2",
                          "5,,1", ",5", "5,0,", "nan,0", "5,inf", "1e400,0", "5;0", ""}) {
    SCOPED_TRACE(bad);
    expect_refused({"w.xml", "--wind", bad}, {"--wind needs SPEED,DIR_DEG[,GUST]", bad});
  }
}

TEST(Options, RecordSizeRefusesWhatIsNotTwoSizesInRange) {
  for (const char* bad : {"0x480", "640x0", "8193x480", "640x8193", "-640x480", "640x480x2",
                          "640X480", "640x480px", "x480", "640*480",
                          // 2^32 + 640 and 2^32 + 480: a parser that wraps at 32 bits reads 640x480
                          "4294967936x480", "640x4294967776", "99999999999999999999x480"}) {
    SCOPED_TRACE(bad);
    expect_refused({"w.xml", "--record-size", bad}, {"--record-size needs WIDTHxHEIGHT", bad});
  }
  const ParseResult r = parse({"w.xml", "--record-size", "8192x1"});
  ASSERT_TRUE(r.options) << r.error;
  EXPECT_EQ(r.options->record_width, 8192);
  EXPECT_EQ(r.options->record_height, 1);
}

TEST(Options, WordChoicesAreExact) {
  expect_refused({"w.xml", "--realism", "Field"}, {"--realism needs field or ideal", "'Field'"});
  expect_refused({"w.xml", "--realism", ""}, {"--realism"});
  expect_refused({"w.xml", "--record-overlay", "yes"}, {"--record-overlay needs 0 or 1", "'yes'"});
  expect_refused({"w.xml", "--radio-backend", "ns2"},
                 {"--radio-backend needs simple or ns3", "'ns2'"});
  expect_refused({"w.xml", "--record-camera", ""}, {"--record-camera needs"});
  expect_refused({"w.xml", "--record-camera", "follow:"}, {"--record-camera needs"});
  expect_refused({"w.xml", "-x"}, {"unknown option -x"});
  expect_refused({"w.xml", "--Rate", "2"}, {"unknown option --Rate"});
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
  expect_refused({"w.xml", "--mavlink-key-file", ::testing::TempDir() + "missing"},
                 {"cannot read"});
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
  const ParseResult r = parse({"w.xml", "--out", "udp:127.0.0.1:14550", "--out",
                               "2=udpin:0.0.0.0:14600", "--out", "udp:10.0.0.{i}:14550"});
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
  EXPECT_EQ(resolve_world_path("empty.xml", UAVSIM_MODELS_DIR),
            std::string(UAVSIM_MODELS_DIR) + "/worlds/empty.xml");
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

TEST(Options, ListWorldsNeedsNoWorld) {
  const ParseResult r = parse({"--list-worlds"});
  ASSERT_TRUE(r.options.has_value()) << r.error;
  EXPECT_TRUE(r.options->list_worlds);
}

TEST(WorldSummary, IsTheFirstSentenceOfTheLeadingComment) {
  const std::string dir = ::testing::TempDir();
  auto write = [&](const std::string& name, const std::string& text) {
    std::ofstream(dir + "/" + name) << text;
    return dir + "/" + name;
  };
  // white space collapsed across lines, up to the first sentence's full stop
  EXPECT_EQ(
      world_summary(write("a.xml", "<!--\n  Two quads:\n  a test.  More words.\n-->\n<mujoco/>")),
      "Two quads: a test");
  // a comment after the first element is not the world's header
  EXPECT_EQ(world_summary(write("b.xml", "<mujoco>\n<!-- inner -->\n</mujoco>")), "");
  EXPECT_EQ(world_summary(write("c.xml", "<mujoco/>")), "");
  EXPECT_EQ(world_summary(dir + "/missing.xml"), "");
  // cut at a word, with an ellipsis, within max_chars
  const std::string cut = world_summary(write("d.xml", "<!-- one two three four five six -->"), 16);
  EXPECT_EQ(cut, "one two three...");
  EXPECT_LE(cut.size(), 16u);
}

TEST(WorldSummary, ListsEveryShippedWorldWithWhatItHolds) {
  const std::string text = list_worlds_text(UAVSIM_MODELS_DIR, "source tree");
  EXPECT_EQ(text.rfind(std::string("# models: ") + UAVSIM_MODELS_DIR + " (source tree)\n", 0), 0u)
      << text;
  for (const std::string& w : shipped_worlds(UAVSIM_MODELS_DIR)) {
    // each world on its own line, with a summary from its header comment
    const std::size_t at = text.find("\n" + w + " ");
    ASSERT_NE(at, std::string::npos) << w << "\n" << text;
    const std::string line = text.substr(at + 1, text.find('\n', at + 1) - at - 1);
    EXPECT_FALSE(world_summary(std::string(UAVSIM_MODELS_DIR) + "/worlds/" + w + ".xml").empty())
        << w;
    EXPECT_GT(line.size(), w.size() + 10) << line;
  }
  EXPECT_NE(text.find("\nmbzirc2017 "), std::string::npos) << text;
}

}  // namespace
}  // namespace uavsim::server::app
