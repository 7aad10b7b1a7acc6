#include "app/options.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <initializer_list>
#include <limits>
#include <sstream>
#include <string>

#include "app/param_file.hpp"
#include "uavsim/common/parse_number.hpp"

namespace uavsim::server::app {

const char* version_string() {
#ifdef UAVSIM_VERSION
  return "uavsim-server " UAVSIM_VERSION " (MuJoCo 2.2, MAVLink 2, sim API protocol 1)";
#else
  return "uavsim-server (MuJoCo 2.2, MAVLink 2, sim API protocol 1)";
#endif
}

const char* usage() {
  return R"(usage: uavsim-server WORLD [options]

Simulates the world and its vehicles. WORLD is a file (MuJoCo MJCF plus uavsim's <uavsim_vehicle>,
<uavsim_grid> and <uavsim_object> elements, models/README.md) or the name of a shipped
world (empty, hexa, grid100, mbzirc2017, mbzirc2020).

simulation:
  --seed N            seed of every random generator (sensor noise, ...); default 1
  --physics-hz HZ     physics rate; default 1000
  --physics-shards N  split the vehicles into N physics shards (1 to 64) stepped in lockstep on a thread
                      pool, or auto (one per hardware thread for 200 vehicles or more); default 1.
                      Vehicles in different shards never touch each other; all touch the ground and the
                      static scene. Only worlds where nothing but vehicles moves, without cameras
                      (--no-cameras), can be sharded (models/README.md "Physics shards")
  --physics-threads N threads stepping the shards (1 to 64); default one per shard, at most the
                      hardware threads. Results do not depend on it
  --control-hz HZ     flight-control rate, rounded to a divisor of the physics rate; default 500
  --rate X            clock: X times real time (default 1); --rate 0 or --fast: as fast as possible
  --fast              same as --rate 0
  --duration S        stop after S seconds of sim time (default: run until interrupted)
  --wait-for-clients N  hold the clock at 0 until N clients (MAVLink or sim API) are connected
  --realism LEVEL     ideal (no wind, perfect sensors, gimbal and cameras: the default) or field (wind,
                      gusts, sensor bias and drift, gimbal lag, camera noise and latency, varied balloons,
                      battery sag with field defaults); over the world's uavsim:realism (docs/protocol.md)
  --wind SPEED,DIR_DEG[,GUST]  mean wind in m/s blowing from DIR_DEG (clockwise from north), turbulence
                      of GUST m/s standard deviation (default: the realism level's)
  --home LAT,LON,ALT[,HDG]  geodetic position of the world origin (degrees, metres above sea level);
                      default: the world's <numeric name="uavsim:home" data="LAT LON ALT"/>, else
                      47.397742,8.545594,488. HDG (ArduPilot SITL's start heading) must be 0 here:
                      each vehicle's heading is its yaw_deg in the world
  --defaults FILE.parm  ArduPilot parameter file (NAME VALUE or NAME,VALUE; # comments) applied to
                      every vehicle at start, after the world's per-vehicle parameters (repeatable)
  --demo              fly vehicle 0 through take-off, three waypoints and landing, print what happened,
                      and exit with 0 if the flight succeeded
  --hover M           every vehicle arms in GUIDED, takes off to M metres (0.5 to 1000) and holds, with
                      no client: the floor a mission's wall time is measured against
  --write-world FILE  write the composed MJCF (plain MuJoCo, opens in mujoco-simulate) and exit
  --models-dir DIR    where vehicles/, objects/ and worlds/ live; default: the environment variable
                      UAVSIM_MODELS_DIR, else PREFIX/share/uavsim/models of an install (beside
                      PREFIX/bin/uavsim-server), else the source tree's models/ the build came from.
                      A world's <include file=...> not found beside it is looked up there too, as if
                      the world were a shipped one (file="../common/ground.xml")
  --list-worlds       the shipped worlds (name and what each holds) and where they are, then exit

MAVLink (per vehicle, ArduCopter on the wire):
  --mavlink-port BASE TCP port of vehicle 0's MAVLink endpoint; vehicle i listens on BASE + 10 i
                      (ArduPilot SITL's convention); default 5760; 0: ephemeral ports; -1: none
  --bind ADDR         address the MAVLink TCP endpoints listen on; default 127.0.0.1 (loopback only)
  --out URL           also speak MAVLink over UDP (repeatable): udp:HOST:PORT sends to a ground
                      station there and answers it on the same socket; udpin:ADDR:PORT listens and
                      answers the first peer. Vehicle i uses PORT + 10 i; a "{i}" in the URL is
                      replaced by the vehicle index instead; "N=URL" is for vehicle N only.
                      Default with a fixed --mavlink-port (not 0 or -1): 0=udp:127.0.0.1:14550, so
                      QGroundControl finds vehicle 0 on its own; --out none: no UDP
  --mavlink-key HEX64 MAVLink 2 signing key (64 hex digits) of every vehicle from the start: frames
                      sent are signed, unsigned ones received are ignored (a client's SETUP_SIGNING
                      replaces it; an all-zero key turns signing off). Prefer --mavlink-key-file or
                      the environment variable UAVSIM_MAVLINK_KEY: arguments are visible to every
                      user of the machine
  --mavlink-key-file FILE  the signing key from a file (64 hex digits)

sim socket API (docs/protocol.md):
  --api-port N        TCP port of the sim socket API; default 5700; 0: an ephemeral port (printed);
                      -1: no API
  --api-bind ADDR     address the sim API listens on; default 127.0.0.1 (loopback only)
  --api-token-file FILE  clients must send this file's first line (the token) before any other op
  --allow-remote-gcs  let gcs_link_open send to hosts other than the API client's own address
  --lockstep-timeout S  drop a lockstep client that takes more than S wall seconds for a tick; default 10
  --watchdog S        report a simulation loop that makes no progress for S wall seconds (with what it
                      was doing); default 10, 0: off. A SIGTERM or SIGINT the loop has not acted on
                      within 5 s ends the process anyway (exit 143 / 130)
  --radio-backend B   the A2A radio's channel: simple (closed form: range or log-distance, seeded loss,
                      TDMA, optional collisions; the default) or ns3 (ns-3's IEEE 802.15.4 lr-wpan: CSMA-CA,
                      ACKs and retries, SINR errors, in the helper program uavsim-ns3-radio); over the
                      world's <text name="uavsim:radio_backend" data="B"/> (docs/protocol.md "Radio")
  --gcs-link-backend B  the GCS link relay's channel: simple (the closed-form relay; the default) or ns3
                      (each datagram over ns-3's 802.11g ad hoc between the vehicle and a ground node, in
                      a uavsim-ns3-radio helper of its own); over the world's
                      <text name="uavsim:gcs_link_backend" data="B"/> (docs/protocol.md "Ground-station link")
  --gcs-position X,Y,Z  where the ground node stands (ENU metres, each within +-100000); over the world's
                      <numeric name="uavsim:gcs_position" data="X Y Z"/>; default: 1.5 m above the mean of
                      the vehicles' start positions

cameras and logs:
  --camera CAM:K=V,...  camera settings over the world's uavsim:camera:CAM text (CAM * for all):
                      width, height, fps, fovy, shadows, reflections, skybox, msaa; field conditions:
                      noise (pixel sd), brightness (gain sd), latency_ms (docs/protocol.md)
  --no-cameras        no offscreen renderer (the camera ops answer not_available)
  --render-cameras CAM[:FORMAT][@FPS],...  render these cameras with no client and discard the frames
                      (repeatable): FORMAT rgb (the default), grey, depth or segmentation; FPS frames
                      per sim second, the camera's own rate (the default) divided by a whole number.
                      No frame is dropped: at --rate 0 the clock waits for the renderer, as for a
                      lockstep client. With --hover, the floor of a mission that subscribes to them
                      (docs/results/performance.md); the summary says how many frames were rendered
  --gl B              how cameras get OpenGL: osmesa (the default: Mesa's off-screen software
                      renderer), egl (EGL without a display: a GPU where there is one, else Mesa's
                      llvmpipe through the surfaceless platform) or auto (egl if it creates a
                      context, else osmesa); the start-up log says which one renders
  --render-threads N  threads rendering camera frames, each with its own GL context: cameras of
                      different vehicles render in parallel (1 to 64); default: one per two hardware
                      threads (1 to 8), at most one per camera. Frames and their order do not depend on it
  --record FILE.mp4   write a video of the run from the world camera "overview" (else the first world
                      camera, else the first camera), 15 frames per second of sim time; in real time
                      it drops frames rather than slow physics, at --rate 0 it keeps every frame
  --record-fps F      frames per second of sim time in the video; default 15
  --record-size WxH   video size; default 640x480
  --record-camera C   what the video shows: overview (the default: the camera above), follow (all
                      vehicles in frame, a camera that tracks their bounding box smoothly, never closer
                      than 8 m), follow:NAME (that vehicle), top (straight down over the vehicles), or
                      the name of any camera of the world
  --record-overlay 0|1  burn sim time, vehicle names and modes, recent events and mission counters into
                      the video's frames; default 1
  --record-layout L   single (the default: the main view alone) or tiled (the vehicles' onboard
                      cameras, up to 4, in a column beside the main view, each labelled)
  --record-tile CAMERA[:MODALITY]  a tile of this camera's rgb (the default), depth or segmentation
                      (false colour) instead of the automatic choice; repeat for more (up to 6)
  --log-dir DIR       write VEHICLE.tlog per vehicle (every MAVLink frame each way, stamped with sim
                      time, as MAVProxy and QGroundControl write them) and events.jsonl (the server's
                      events, one JSON object a line)
  --quiet             print only errors and the result (no event lines, no summary)
  --list-params       the flight controller's parameters as a Markdown table (docs/parameters.md)
  --print-schedule    print the step schedule (its phases, and who runs in each, in order) before the
                      clock starts
  --version           the version
  --help              this text
)";
}

namespace {

// --record-tile: tiles in the column beside the main view (each a sixth of its height at least)
constexpr size_t kMaxRecordTiles = 6;

// one option's value, checked: a number in [lo, hi], integral when asked
struct NumberRule {
  double lo = -std::numeric_limits<double>::infinity();
  double hi = std::numeric_limits<double>::infinity();
  bool integer = false;
  const char* what = "a number";
};

std::string format_number(double v) {
  std::ostringstream os;
  os << v;
  return os.str();
}

std::optional<double> parse_number(const std::string& flag, const std::string& text,
                                   const NumberRule& rule, std::string* why) {
  char* end = nullptr;
  const double v = std::strtod(text.c_str(), &end);
  const bool parsed = !text.empty() && end != text.c_str() && *end == '\0' && std::isfinite(v);
  const bool integral = parsed && std::floor(v) == v;
  if (parsed && (!rule.integer || integral) && v >= rule.lo && v <= rule.hi) return v;
  std::string range;
  if (std::isfinite(rule.lo) && std::isfinite(rule.hi)) {
    range = " from " + format_number(rule.lo) + " to " + format_number(rule.hi);
  } else if (std::isfinite(rule.lo)) {
    range =
        rule.lo == 0.0 && rule.integer ? " (0 or more)" : " of at least " + format_number(rule.lo);
  }
  *why = flag + " needs " + rule.what + range + ", got '" + text + "'";
  return std::nullopt;
}

std::optional<std::string> read_first_line(const std::string& flag, const std::string& path,
                                           std::string* why) {
  std::ifstream in(path);
  if (!in) {
    *why = flag + ": cannot read '" + path + "'";
    return std::nullopt;
  }
  std::string line;
  std::getline(in, line);
  const auto first = line.find_first_not_of(" \t\r");
  const auto last = line.find_last_not_of(" \t\r");
  if (first == std::string::npos) {
    *why = flag + ": '" + path + "' is empty";
    return std::nullopt;
  }
  return line.substr(first, last - first + 1);
}

// the choices as a list for a message: "a, b or c"
std::string one_of(std::initializer_list<const char*> choices) {
  std::string list;
  std::size_t k = 0;
  for (const char* c : choices) {
    if (k > 0) list += k + 1 == choices.size() ? " or " : ", ";
    list += c;
    ++k;
  }
  return list;
}

// the comma-separated numbers of text when there are min_count to max_count of them, each part a
// whole finite number (common/parse_number.hpp's rule); empty when not
std::vector<double> number_list(const std::string& text, std::size_t min_count,
                                std::size_t max_count) {
  std::vector<double> v;
  std::stringstream ss(text);
  std::string part;
  while (std::getline(ss, part, ',')) {
    double x = 0.0;
    if (!uavsim::common::parse_double(part.c_str(), -HUGE_VAL, HUGE_VAL, &x)) return {};
    v.push_back(x);
  }
  // getline drops an empty last part ("3,90,"): the commas count the parts
  const bool shape = v.size() >= min_count && v.size() <= max_count &&
                     std::count(text.begin(), text.end(), ',') + 1 == static_cast<long>(v.size());
  return shape ? v : std::vector<double>{};
}

std::optional<WindOption> parse_wind(const std::string& text, std::string* why) {
  const std::vector<double> v = number_list(text, 2, 3);
  if (v.empty() || v[0] < 0 || v[0] > 50 || v[1] < -360 || v[1] > 360 ||
      (v.size() == 3 && (v[2] < 0 || v[2] > 20))) {
    *why =
        "--wind needs SPEED,DIR_DEG[,GUST] (speed 0..50 m/s, direction it blows from -360..360 "
        "degrees "
        "clockwise from north, turbulence 0..20 m/s standard deviation), got '" +
        text + "'";
    return std::nullopt;
  }
  WindOption w;
  w.speed_m_s = v[0];
  w.from_deg = v[1];
  if (v.size() == 3) w.turbulence_sd_m_s = v[2];
  return w;
}

std::optional<std::array<double, 3>> parse_gcs_position(const std::string& text, std::string* why) {
  const std::vector<double> v = number_list(text, 3, 3);
  if (v.empty() || std::any_of(v.begin(), v.end(), [](double x) { return std::abs(x) > 100000.0; })) {
    *why = "--gcs-position needs X,Y,Z (ENU metres, each within +-100000), got '" + text + "'";
    return std::nullopt;
  }
  return std::array<double, 3>{v[0], v[1], v[2]};
}

std::optional<HomeOption> parse_home(const std::string& text, std::string* why) {
  const std::vector<double> v = number_list(text, 3, 4);
  HomeOption h;
  const bool shape = !v.empty();
  if (shape) {
    h.lat_deg = v[0];
    h.lon_deg = v[1];
    h.alt_m = v[2];
    h.heading_deg = v.size() == 4 ? v[3] : 0.0;
  }
  if (!shape || std::abs(h.lat_deg) > 90.0 || std::abs(h.lon_deg) > 180.0 || h.alt_m < -500.0 ||
      h.alt_m > 10000.0) {
    *why =
        "--home needs LAT,LON,ALT (latitude -90..90, longitude -180..180 degrees, altitude "
        "-500..10000 m "
        "above sea level), got '" +
        text + "'";
    return std::nullopt;
  }
  if (h.heading_deg != 0.0) {
    *why = "--home: a start heading (" + text.substr(text.rfind(',') + 1) +
           ") is not taken from the command line here: each vehicle's heading is its yaw_deg in "
           "the world file "
           "(give LAT,LON,ALT or a heading of 0)";
    return std::nullopt;
  }
  return h;
}

}  // namespace

std::optional<std::array<uint8_t, 32>> parse_signing_key(const std::string& text) {
  const auto first = text.find_first_not_of(" \t\r\n");
  const auto last = text.find_last_not_of(" \t\r\n");
  if (first == std::string::npos) return std::nullopt;
  const std::string hex = text.substr(first, last - first + 1);
  if (hex.size() != 64) return std::nullopt;
  std::array<uint8_t, 32> key{};
  for (std::size_t k = 0; k < key.size(); ++k) {
    int byte = 0;
    for (std::size_t d = 0; d < 2; ++d) {
      const char c = hex[2 * k + d];
      if (!std::isxdigit(static_cast<unsigned char>(c))) return std::nullopt;
      const int nibble =
          std::isdigit(static_cast<unsigned char>(c)) ? c - '0' : std::tolower(c) - 'a' + 10;
      byte = byte * 16 + nibble;
    }
    key[k] = static_cast<uint8_t>(byte);
  }
  return key;
}

std::optional<UdpTarget> udp_target(const UdpOut& out, int vehicle, std::string* why) {
  why->clear();
  if (out.vehicle && *out.vehicle != vehicle) return std::nullopt;
  // "{i}": the vehicle index in place; else vehicle i on PORT + 10 i
  std::string url = out.spec;
  const bool pattern = url.find("{i}") != std::string::npos;
  for (auto at = url.find("{i}"); at != std::string::npos; at = url.find("{i}")) {
    url.replace(at, 3, std::to_string(vehicle));
  }
  UdpTarget t;
  std::string rest;
  if (url.rfind("udpin:", 0) == 0) {
    t.listen = true;
    rest = url.substr(6);
  } else if (url.rfind("udp:", 0) == 0) {
    rest = url.substr(4);
  } else {
    *why = "--out needs udp:HOST:PORT or udpin:ADDR:PORT, got '" + out.spec + "'";
    return std::nullopt;
  }
  const auto colon = rest.rfind(':');
  t.host = colon == std::string::npos ? "" : rest.substr(0, colon);
  const std::string port_text = colon == std::string::npos ? "" : rest.substr(colon + 1);
  char* end = nullptr;
  const long port = std::strtol(port_text.c_str(), &end, 10);
  if (t.host.empty() || port_text.empty() || *end != '\0' || port < 1 || port > 65535) {
    *why = "--out '" + out.spec + "': needs a host and a port from 1 to 65535";
    return std::nullopt;
  }
  const long offset = pattern || out.vehicle ? 0 : 10L * vehicle;
  if (port + offset > 65535) {
    *why = "--out '" + out.spec + "': vehicle " + std::to_string(vehicle) + " would use port " +
           std::to_string(port + offset) + ", past 65535 (use a lower port or \"{i}\")";
    return std::nullopt;
  }
  t.port = static_cast<int>(port + offset);
  return t;
}

std::optional<std::string> port_range_error(const std::string& flag, int base_port,
                                            std::size_t vehicle_count) {
  if (base_port <= 0 || vehicle_count == 0) return std::nullopt;
  const long last = base_port + 10L * static_cast<long>(vehicle_count - 1);
  if (last <= 65535) return std::nullopt;
  const long highest_base = 65535 - 10L * static_cast<long>(vehicle_count - 1);
  std::string msg = flag + " " + std::to_string(base_port) + ": the world has " +
                    std::to_string(vehicle_count) + " vehicles, and the last would use port " +
                    std::to_string(last) + ", past 65535; ";
  if (highest_base >= 1) msg += "use a base of at most " + std::to_string(highest_base) + " or ";
  return msg + flag + " 0 (ephemeral ports, printed at start)";
}

bool is_loopback_address(const std::string& address) {
  return address == "localhost" || address.rfind("127.", 0) == 0;
}

ParseResult parse_args(const std::vector<std::string>& args, const EnvLookup& env) {
  ParseResult r;
  Options o;
  r.exit_code = 2;
  auto fail = [&r](std::string why) {
    r.error = std::move(why);
    r.options.reset();
    return r;
  };
  std::optional<std::string> key_text;  // --mavlink-key or the key file's contents
  std::string key_source;
  for (std::size_t i = 0; i < args.size(); ++i) {
    const std::string& a = args[i];
    std::string why;
    // the option's value, or a failure naming the option
    auto value = [&](std::string* out) {
      if (i + 1 >= args.size()) {
        why = a + " needs a value (see --help)";
        return false;
      }
      *out = args[++i];
      return true;
    };
    auto number = [&](const NumberRule& rule, double* out) {
      std::string text;
      if (!value(&text)) return false;
      const auto v = parse_number(a, text, rule, &why);
      if (v) *out = *v;
      return v.has_value();
    };
    // a value that must be one of `choices`, or a failure naming them
    auto choice = [&](std::initializer_list<const char*> choices, std::string* out) {
      if (!value(out)) return false;
      for (const char* c : choices) {
        if (*out == c) return true;
      }
      why = a + " needs " + one_of(choices) + ", got '" + *out + "'";
      return false;
    };
    std::string v;
    double x = 0.0;
    bool ok = true;
    if (a == "--help" || a == "-h") {
      r.output = usage();
      r.exit_code = 0;
      return r;
    } else if (a == "--list-params") {
      r.output = params_markdown();
      r.exit_code = 0;
      return r;
    } else if (a == "--list-worlds") {
      o.list_worlds = true;
    } else if (a == "--print-schedule") {
      o.print_schedule = true;
    } else if (a == "--version") {
      r.output = std::string(version_string()) + "\n";
      r.exit_code = 0;
      return r;
    } else if (a == "--seed") {
      // seeds are integers up to 2^53 (exact in a double)
      ok = number({0, 9007199254740992.0, true, "an integer"}, &x);
      o.seed = static_cast<uint64_t>(x);
    } else if (a == "--physics-hz") {
      ok = number({1, 100000, false, "a rate in Hz"}, &o.physics_hz);
    } else if (a == "--physics-shards") {
      // 0 stands for auto (physics/world_composer.hpp)
      if ((ok = value(&v)) && v == "auto") {
        o.physics_shards = 0;
      } else if (ok) {
        --i;
        ok = number({1, 64, true, "a shard count or auto"}, &x);
        o.physics_shards = static_cast<int>(x);
      }
    } else if (a == "--physics-threads") {
      ok = number({1, 64, true, "a thread count"}, &x);
      o.physics_threads = static_cast<int>(x);
    } else if (a == "--control-hz") {
      ok = number({1, 100000, false, "a rate in Hz"}, &o.control_hz);
    } else if (a == "--rate") {
      ok = number({0, 1e6, false, "a factor of real time (0: as fast as possible)"}, &o.rate);
    } else if (a == "--fast") {
      o.rate = 0.0;
    } else if (a == "--duration") {
      ok = number({0, 1e9, false, "seconds of sim time"}, &o.duration_s);
    } else if (a == "--wait-for-clients") {
      ok = number({0, 100000, true, "a number of clients"}, &x);
      o.wait_for_clients = static_cast<int>(x);
    } else if (a == "--home") {
      if ((ok = value(&v))) {
        o.home = parse_home(v, &why);
        ok = o.home.has_value();
      }
    } else if (a == "--realism") {
      if ((ok = choice({"field", "ideal"}, &v))) o.realism = v;
    } else if (a == "--wind") {
      if ((ok = value(&v))) {
        o.wind = parse_wind(v, &why);
        ok = o.wind.has_value();
      }
    } else if (a == "--defaults") {
      if ((ok = value(&v))) o.defaults_files.push_back(v);
    } else if (a == "--demo") {
      o.demo = true;
    } else if (a == "--hover") {
      ok = number({0.5, 1000, false, "metres of altitude"}, &x);
      if (ok) o.hover_m = x;
    } else if (a == "--write-world") {
      if ((ok = value(&v))) o.write_world_path = v;
    } else if (a == "--models-dir") {
      if ((ok = value(&v))) o.models_dir = v;
    } else if (a == "--mavlink-port") {
      ok = number({-1, 65535, true, "a port (0: ephemeral, -1: none)"}, &x);
      o.mavlink_base_port = static_cast<int>(x);
    } else if (a == "--bind") {
      if ((ok = value(&v))) o.bind_address = v;
    } else if (a == "--out") {
      if ((ok = value(&v))) {
        o.udp_outs_explicit = true;
        if (v != "none") {
          UdpOut out;
          const auto eq = v.find('=');
          if (eq != std::string::npos && eq > 0 && v.find(':') > eq) {
            const auto n = parse_number(a, v.substr(0, eq),
                                        {0, 100000, true, "a vehicle index before '='"}, &why);
            ok = n.has_value();
            if (n) out.vehicle = static_cast<int>(*n);
            out.spec = v.substr(eq + 1);
          } else {
            out.spec = v;
          }
          // check the URL as vehicle 0 (or the named vehicle) would use it
          ok = ok && udp_target(out, out.vehicle.value_or(0), &why).has_value();
          if (ok) o.udp_outs.push_back(out);
        }
      }
    } else if (a == "--mavlink-key") {
      if ((ok = value(&v))) {
        key_text = v;
        key_source = a;
      }
    } else if (a == "--mavlink-key-file") {
      if ((ok = value(&v))) {
        key_text = read_first_line(a, v, &why);
        key_source = a + " " + v;
        ok = key_text.has_value();
      }
    } else if (a == "--api-port") {
      ok = number({-1, 65535, true, "a port (0: ephemeral, -1: none)"}, &x);
      o.api_port = static_cast<int>(x);
    } else if (a == "--api-bind") {
      if ((ok = value(&v))) o.api_bind_address = v;
    } else if (a == "--api-token-file") {
      if ((ok = value(&v))) {
        o.api_token = read_first_line(a, v, &why);
        ok = o.api_token.has_value();
      }
    } else if (a == "--allow-remote-gcs") {
      o.allow_remote_gcs = true;
    } else if (a == "--lockstep-timeout") {
      ok = number({0.001, 86400, false, "wall seconds"}, &o.lockstep_timeout_s);
    } else if (a == "--watchdog") {
      ok = number({0.0, 86400, false, "wall seconds"}, &o.watchdog_s);
    } else if (a == "--radio-backend") {
      if ((ok = choice({"simple", "ns3"}, &v))) o.radio_backend = v;
    } else if (a == "--gcs-link-backend") {
      if ((ok = choice({"simple", "ns3"}, &v))) o.gcs_link_backend = v;
    } else if (a == "--gcs-position") {
      if ((ok = value(&v))) {
        o.gcs_position = parse_gcs_position(v, &why);
        ok = o.gcs_position.has_value();
      }
    } else if (a == "--camera") {
      if ((ok = value(&v))) o.camera_overrides.push_back(v);
    } else if (a == "--no-cameras") {
      o.cameras = false;
    } else if (a == "--render-cameras") {
      if ((ok = value(&v))) ok = parse_render_cameras(v, &o.render_cameras, &why);
    } else if (a == "--gl") {
      if ((ok = choice({"egl", "osmesa", "auto"}, &v))) o.gl_backend = v;
    } else if (a == "--render-threads") {
      ok = number({1, 64, true, "a thread count"}, &x);
      o.render_threads = static_cast<int>(x);
    } else if (a == "--record") {
      if ((ok = value(&v))) o.record_path = v;
    } else if (a == "--record-fps") {
      ok = number({0.001, 1000, false, "frames per second"}, &o.record_fps);
    } else if (a == "--record-camera") {
      if ((ok = value(&v))) {
        ok = !v.empty() && v != "follow:";
        if (!ok) why = "--record-camera needs overview, follow, follow:NAME, top or a camera name";
        o.record_camera = v;
      }
    } else if (a == "--record-overlay") {
      if ((ok = choice({"0", "1"}, &v))) o.record_overlay = v == "1";
    } else if (a == "--record-tile") {
      if ((ok = value(&v))) {
        const std::string modality =
            v.find(':') == std::string::npos ? "rgb" : v.substr(v.find(':') + 1);
        ok = !v.empty() && v.front() != ':' &&
             (modality == "rgb" || modality == "depth" || modality == "segmentation") &&
             o.record_tiles.size() < kMaxRecordTiles;
        if (!ok) {
          why = "--record-tile needs CAMERA or CAMERA:rgb|depth|segmentation, at most " +
                std::to_string(kMaxRecordTiles) + " times, got '" + v + "'";
        }
        o.record_tiles.push_back(v);
        o.record_tiled = true;
      }
    } else if (a == "--record-layout") {
      if ((ok = choice({"single", "tiled"}, &v))) o.record_tiled = v == "tiled";
    } else if (a == "--record-size") {
      if ((ok = value(&v))) {
        // each side digits only, range-checked as a long before the cast (sscanf's %d overflows
        // undefined: it read 4294967936x480, 2^32 + 640, as 640x480)
        auto side = [](const std::string& text, long* out) {
          char* end = nullptr;
          *out = std::strtol(text.c_str(), &end, 10);
          return !text.empty() && std::isdigit(static_cast<unsigned char>(text[0])) &&
                 *end == '\0' && *out >= 1 && *out <= 8192;
        };
        const auto x_at = v.find('x');
        long w = 0, h = 0;
        ok = x_at != std::string::npos && side(v.substr(0, x_at), &w) &&
             side(v.substr(x_at + 1), &h);
        if (!ok) why = "--record-size needs WIDTHxHEIGHT (1 to 8192 each), got '" + v + "'";
        o.record_width = static_cast<int>(w);
        o.record_height = static_cast<int>(h);
      }
    } else if (a == "--log-dir") {
      if ((ok = value(&v))) o.log_dir = v;
    } else if (a == "--quiet") {
      o.quiet = true;
    } else if (!a.empty() && a[0] == '-') {
      return fail("unknown option " + a + " (see --help)");
    } else if (o.world_path.empty()) {
      o.world_path = a;
    } else {
      return fail("more than one world given (" + o.world_path + ", " + a + ")");
    }
    if (!ok) return fail(why);
  }
  // the signing key: an option, else the environment
  if (!key_text) {
    if (auto e = env("UAVSIM_MAVLINK_KEY"); e && !e->empty()) {
      key_text = *e;
      key_source = "UAVSIM_MAVLINK_KEY";
    }
  }
  if (key_text) {
    o.mavlink_key = parse_signing_key(*key_text);
    if (!o.mavlink_key)
      return fail(key_source + ": a MAVLink signing key is 64 hex digits (32 bytes)");
  }
  if (!o.cameras && !o.render_cameras.empty())
    return fail("--render-cameras needs the renderer, which --no-cameras turns off");
  if (o.world_path.empty() && !o.version && !o.list_worlds)
    return fail("no world given (a world file or a shipped world's name; see --help)");
  r.options = std::move(o);
  r.exit_code = 0;
  return r;
}

}  // namespace uavsim::server::app
