#include "render/camera_setup.hpp"

#include <mujoco/mujoco.h>

#include <cmath>
#include <cstdlib>
#include <cstring>
#include <sstream>

namespace uavsim::server::render {

namespace {

constexpr const char* kTextPrefix = "uavsim:camera:";

double number_of(const std::string& key, const std::string& value, const std::string& where) {
  char* end = nullptr;
  const double v = std::strtod(value.c_str(), &end);
  if (value.empty() || *end != '\0' || !std::isfinite(v)) {
    throw std::invalid_argument(where + ": " + key + " needs a number, got '" + value + "'");
  }
  return v;
}

int int_of(const std::string& key, const std::string& value, const std::string& where, int lo, int hi) {
  const double v = number_of(key, value, where);
  if (std::floor(v) != v || v < lo || v > hi) {
    throw std::invalid_argument(where + ": " + key + " must be an integer in [" + std::to_string(lo) + ", " +
                                std::to_string(hi) + "], got '" + value + "'");
  }
  return static_cast<int>(v);
}

}  // namespace

Modalities modalities_of(const std::string& text, const std::string& where) {
  // '+'-separated names (',' separates the options), each at most once, at least one
  Modalities m{false, false, false, false};
  size_t start = 0;
  for (;;) {
    const size_t plus = text.find('+', start);
    const std::string name = text.substr(start, plus == std::string::npos ? std::string::npos : plus - start);
    bool* slot = name == "rgb"            ? &m.rgb
                 : name == "grey"         ? &m.grey
                 : name == "depth"        ? &m.depth
                 : name == "segmentation" ? &m.segmentation
                                          : nullptr;
    if (slot == nullptr) {
      throw std::invalid_argument(where + ": unknown modality '" + name +
                                  "' in modalities (rgb, grey, depth, segmentation, joined by '+')");
    }
    if (*slot) throw std::invalid_argument(where + ": modality '" + name + "' given twice");
    *slot = true;
    if (plus == std::string::npos) break;
    start = plus + 1;
  }
  return m;
}

void apply_camera_options(const std::string& text, const std::string& where, CameraConfig* c) {
  std::string spaced = text;
  for (char& ch : spaced) {
    if (ch == ',') ch = ' ';
  }
  std::istringstream in(spaced);
  std::string pair;
  while (in >> pair) {
    const size_t eq = pair.find('=');
    if (eq == std::string::npos) {
      throw std::invalid_argument(where + ": '" + pair + "' is not key=value");
    }
    const std::string key = pair.substr(0, eq);
    const std::string value = pair.substr(eq + 1);
    if (key == "width") {
      c->width_px = int_of(key, value, where, 1, 8192);
    } else if (key == "height") {
      c->height_px = int_of(key, value, where, 1, 8192);
    } else if (key == "fps") {
      c->fps_hz = number_of(key, value, where);
      if (!(c->fps_hz > 0)) throw std::invalid_argument(where + ": fps must be > 0, got '" + value + "'");
    } else if (key == "fovy") {
      const double f = number_of(key, value, where);
      if (!(f > 0 && f < 180)) throw std::invalid_argument(where + ": fovy must be in (0, 180)");
      c->fovy_deg = f;
    } else if (key == "shadows") {
      c->flags.shadows = int_of(key, value, where, 0, 1) != 0;
    } else if (key == "reflections") {
      c->flags.reflections = int_of(key, value, where, 0, 1) != 0;
    } else if (key == "skybox") {
      c->flags.skybox = int_of(key, value, where, 0, 1) != 0;
    } else if (key == "msaa") {
      c->flags.msaa_samples = int_of(key, value, where, 0, 16);
    } else if (key == "noise") {
      c->noise_sd = number_of(key, value, where);
      if (!(c->noise_sd >= 0 && c->noise_sd <= 100)) throw std::invalid_argument(where + ": noise must be in [0, 100]");
    } else if (key == "brightness") {
      c->brightness_sd = number_of(key, value, where);
      if (!(c->brightness_sd >= 0 && c->brightness_sd <= 1)) {
        throw std::invalid_argument(where + ": brightness must be in [0, 1]");
      }
    } else if (key == "latency_ms") {
      const double ms = number_of(key, value, where);
      if (!(ms >= 0 && ms <= 10000)) throw std::invalid_argument(where + ": latency_ms must be in [0, 10000]");
      c->latency_s = ms / 1000.0;
    } else if (key == "modalities") {
      c->modalities = modalities_of(value, where);
    } else if (key == "depth_noise") {
      c->depth_noise_m = number_of(key, value, where);
      if (!(c->depth_noise_m >= 0 && c->depth_noise_m <= 1)) {
        throw std::invalid_argument(where + ": depth_noise must be in [0, 1] m (the SD at 1 m)");
      }
    } else if (key == "depth_dropout") {
      c->depth_dropout = number_of(key, value, where);
      if (!(c->depth_dropout >= 0 && c->depth_dropout <= 1)) {
        throw std::invalid_argument(where + ": depth_dropout must be in [0, 1]");
      }
    } else if (key == "depth_max_m") {
      const double m = number_of(key, value, where);
      if (!(m > 0 && m <= 1e6)) throw std::invalid_argument(where + ": depth_max_m must be in (0, 1e6]");
      c->depth_max_m = m;
    } else {
      throw std::invalid_argument(where + ": unknown camera option '" + key +
                                  "' (width, height, fps, fovy, shadows, reflections, skybox, msaa, noise, "
                                  "brightness, latency_ms, modalities, depth_noise, depth_dropout, depth_max_m)");
    }
  }
}

std::vector<CameraSetup> discover_cameras(const mjModel* m, const CameraOwners& owners,
                                          const std::vector<std::string>& overrides, double control_hz) {
  std::vector<CameraSetup> cameras;
  for (int id = 0; id < m->ncam; ++id) {
    const char* name = mj_id2name(m, mjOBJ_CAMERA, id);
    if (name == nullptr || name[0] == '\0') continue;
    CameraSetup s;
    s.config.camera = name;
    s.config.width_px = 640;
    s.config.height_px = 480;
    s.config.fps_hz = 15.0;
    s.config.format = PixelFormat::kRgb8;
    const int body = m->cam_bodyid[id];
    const auto g = owners.gimbal_body_vehicle.find(body);
    if (g != owners.gimbal_body_vehicle.end()) {
      s.vehicle = g->second;
    } else {
      for (size_t v = 0; v < owners.vehicle_root_bodies.size(); ++v) {
        if (owners.vehicle_root_bodies[v].first == m->body_rootid[body] && body != 0) s.vehicle = static_cast<int>(v);
      }
    }
    if (s.vehicle >= 0 && static_cast<size_t>(s.vehicle) < owners.vehicle_root_bodies.size()) {
      s.vehicle_name = owners.vehicle_root_bodies[static_cast<size_t>(s.vehicle)].second;
    }
    const std::string text_name = std::string(kTextPrefix) + name;
    const int t = mj_name2id(m, mjOBJ_TEXT, text_name.c_str());
    if (t >= 0) apply_camera_options(m->text_data + m->text_adr[t], "custom text " + text_name, &s.config);
    cameras.push_back(std::move(s));
  }
  // custom texts that name no camera are mistakes
  for (int t = 0; t < m->ntext; ++t) {
    const char* n = mj_id2name(m, mjOBJ_TEXT, t);
    if (n == nullptr || std::strncmp(n, kTextPrefix, std::strlen(kTextPrefix)) != 0) continue;
    if (mj_name2id(m, mjOBJ_CAMERA, n + std::strlen(kTextPrefix)) < 0) {
      throw std::invalid_argument(std::string("custom text ") + n + ": the world has no camera named '" +
                                  (n + std::strlen(kTextPrefix)) + "'");
    }
  }
  for (const std::string& o : overrides) {
    const size_t colon = o.find(':');
    if (colon == std::string::npos) {
      throw std::invalid_argument("--camera " + o + ": expected CAMNAME:key=value,... (or *:key=value,...)");
    }
    const std::string cam = o.substr(0, colon);
    bool matched = false;
    for (CameraSetup& s : cameras) {
      if (cam == "*" || s.config.camera == cam) {
        apply_camera_options(o.substr(colon + 1), "--camera " + o, &s.config);
        matched = true;
      }
    }
    if (!matched && cam != "*") {
      std::string names;
      for (const CameraSetup& s : cameras) names += (names.empty() ? "" : ", ") + s.config.camera;
      throw std::invalid_argument("--camera " + o + ": the world has no camera named '" + cam + "' (cameras: " +
                                  (names.empty() ? "none" : names) + ")");
    }
  }
  for (const CameraSetup& s : cameras) {
    if (!(s.config.fps_hz <= control_hz * (1 + 1e-9))) {
      throw std::invalid_argument("camera '" + s.config.camera + "': fps " + std::to_string(s.config.fps_hz) +
                                  " is above the control rate " + std::to_string(control_hz) +
                                  " Hz: frames are taken at control steps, so a camera's frame period must be at "
                                  "least one control step");
    }
  }
  return cameras;
}

}  // namespace uavsim::server::render
