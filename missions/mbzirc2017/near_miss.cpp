#include "near_miss.hpp"

#include <tinyxml2.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <sstream>
#include <stdexcept>

#include "uavsim/common/angles.hpp"

namespace uavsim::missions::mbzirc2017 {

namespace {

constexpr int kRimPoints = 24;
constexpr int kAxisPoints = 9;
constexpr double kFar_m = 8.0;  // farther from the truck: one bounding sphere is enough

std::vector<double> numbers(const char* text) {
  std::vector<double> out;
  if (text == nullptr) return out;
  std::istringstream in(text);
  double v = 0.0;
  while (in >> v) out.push_back(v);
  return out;
}

[[noreturn]] void fail(const std::string& path, const std::string& what) {
  throw std::runtime_error(path + ": " + what);
}

Eigen::Vector3d vec3(const std::string& path, const std::string& geom, const char* attr,
                     const char* text, const Eigen::Vector3d& fallback) {
  if (text == nullptr) return fallback;
  const std::vector<double> v = numbers(text);
  if (v.size() != 3 || !std::isfinite(v[0]) || !std::isfinite(v[1]) || !std::isfinite(v[2])) {
    fail(path, "geom '" + geom + "': " + attr + " needs 3 numbers");
  }
  return Eigen::Vector3d(v[0], v[1], v[2]);
}

// contype | conaffinity of each default class, inherited down the <default> tree
struct Collision {
  std::optional<int> contype, conaffinity;
};

void read_defaults(const tinyxml2::XMLElement* d, Collision inherited,
                   std::map<std::string, Collision>* classes) {
  for (const tinyxml2::XMLElement* c = d->FirstChildElement(); c; c = c->NextSiblingElement()) {
    if (std::string(c->Name()) == "geom") {
      int v = 0;
      if (c->QueryIntAttribute("contype", &v) == tinyxml2::XML_SUCCESS) inherited.contype = v;
      if (c->QueryIntAttribute("conaffinity", &v) == tinyxml2::XML_SUCCESS)
        inherited.conaffinity = v;
    }
  }
  if (const char* name = d->Attribute("class")) (*classes)[name] = inherited;
  for (const tinyxml2::XMLElement* c = d->FirstChildElement("default"); c;
       c = c->NextSiblingElement("default")) {
    read_defaults(c, inherited, classes);
  }
}

struct Geom {
  std::string name, type;
  const tinyxml2::XMLElement* element;
};

// the colliding geoms of the first body of the worldbody
std::vector<Geom> colliding_geoms(const std::string& path, tinyxml2::XMLDocument* doc) {
  if (doc->LoadFile(path.c_str()) != tinyxml2::XML_SUCCESS) fail(path, "cannot read the MJCF");
  const tinyxml2::XMLElement* root = doc->FirstChildElement("mujoco");
  if (root == nullptr) fail(path, "no <mujoco>");
  std::map<std::string, Collision> classes;
  for (const tinyxml2::XMLElement* d = root->FirstChildElement("default"); d;
       d = d->NextSiblingElement("default")) {
    read_defaults(d, Collision{}, &classes);
  }
  const tinyxml2::XMLElement* world = root->FirstChildElement("worldbody");
  const tinyxml2::XMLElement* body = world ? world->FirstChildElement("body") : nullptr;
  if (body == nullptr) fail(path, "no <body> in <worldbody>");
  const char* childclass = body->Attribute("childclass");
  std::vector<Geom> out;
  for (const tinyxml2::XMLElement* g = body->FirstChildElement(); g; g = g->NextSiblingElement()) {
    const std::string kind = g->Name();
    if (kind == "body")
      fail(path, "nested body '" + std::string(g->Attribute("name") ? g->Attribute("name") : "") +
                     "' is not scored");
    if (kind != "geom") continue;
    const std::string name = g->Attribute("name") ? g->Attribute("name") : "";
    const char* cls = g->Attribute("class") ? g->Attribute("class") : childclass;
    Collision c = cls != nullptr && classes.count(cls) ? classes[cls] : Collision{};
    int v = 0;
    if (g->QueryIntAttribute("contype", &v) == tinyxml2::XML_SUCCESS) c.contype = v;
    if (g->QueryIntAttribute("conaffinity", &v) == tinyxml2::XML_SUCCESS) c.conaffinity = v;
    // MuJoCo's defaults: contype = conaffinity = 1
    if (c.contype.value_or(1) == 0 && c.conaffinity.value_or(1) == 0) continue;
    for (const char* rot : {"quat", "euler", "axisangle", "xyaxes", "zaxis"}) {
      if (g->Attribute(rot) != nullptr) {
        fail(path, "geom '" + name + "': a rotated colliding geom (" + rot + ") is not scored");
      }
    }
    out.push_back({name, g->Attribute("type") ? g->Attribute("type") : "sphere", g});
  }
  return out;
}

double size_at(const std::string& path, const Geom& g, size_t i) {
  const std::vector<double> s = numbers(g.element->Attribute("size"));
  if (s.size() <= i || !(s[i] > 0.0) || !std::isfinite(s[i])) {
    fail(path, "geom '" + g.name + "': size needs " + std::to_string(i + 1) + " positive numbers");
  }
  return s[i];
}

}  // namespace

TruckShape load_truck_shape(const std::string& mjcf_path) {
  tinyxml2::XMLDocument doc;
  TruckShape out;
  bool deck = false;
  for (const Geom& g : colliding_geoms(mjcf_path, &doc)) {
    if (g.type != "box")
      fail(mjcf_path, "geom '" + g.name + "': only boxes are scored on the truck");
    BodyBox b;
    b.name = g.name;
    b.centre_m =
        vec3(mjcf_path, g.name, "pos", g.element->Attribute("pos"), Eigen::Vector3d::Zero());
    b.half_m = Eigen::Vector3d(size_at(mjcf_path, g, 0), size_at(mjcf_path, g, 1),
                               size_at(mjcf_path, g, 2));
    if (g.name.rfind("deck", 0) == 0) {
      if (deck) fail(mjcf_path, "more than one deck geom");
      out.deck = b;
      deck = true;
    } else {
      out.parts.push_back(b);
    }
  }
  if (!deck) fail(mjcf_path, "no colliding geom named deck*");
  return out;
}

VehicleShape load_vehicle_shape(const std::string& mjcf_path) {
  tinyxml2::XMLDocument doc;
  VehicleShape out;
  std::vector<std::pair<Eigen::Vector3d, Eigen::Vector3d>> capsules;
  for (const Geom& g : colliding_geoms(mjcf_path, &doc)) {
    const Eigen::Vector3d pos =
        vec3(mjcf_path, g.name, "pos", g.element->Attribute("pos"), Eigen::Vector3d::Zero());
    if (g.type == "cylinder") {
      // two rims and the two face centres
      const double r = size_at(mjcf_path, g, 0), hh = size_at(mjcf_path, g, 1);
      for (const double z : {-hh, hh}) {
        out.spheres.push_back({pos + Eigen::Vector3d(0, 0, z), 0.0});
        for (int k = 0; k < kRimPoints; ++k) {
          const double a = 2.0 * common::kPi * k / kRimPoints;
          out.spheres.push_back({pos + Eigen::Vector3d(r * std::cos(a), r * std::sin(a), z), 0.0});
        }
      }
    } else if (g.type == "capsule" && g.element->Attribute("fromto") != nullptr) {
      const std::vector<double> f = numbers(g.element->Attribute("fromto"));
      if (f.size() != 6) fail(mjcf_path, "geom '" + g.name + "': fromto needs 6 numbers");
      const Eigen::Vector3d a(f[0], f[1], f[2]), b(f[3], f[4], f[5]);
      const double r = size_at(mjcf_path, g, 0);
      for (int k = 0; k < kAxisPoints; ++k) {
        out.spheres.push_back({a + (b - a) * (static_cast<double>(k) / (kAxisPoints - 1)), r});
      }
      capsules.emplace_back(a - Eigen::Vector3d(0, 0, r), b - Eigen::Vector3d(0, 0, r));
    } else if (g.type == "sphere") {
      out.spheres.push_back({pos, size_at(mjcf_path, g, 0)});
    } else {
      fail(mjcf_path, "geom '" + g.name + "': type " + g.type + " is not scored");
    }
  }
  if (out.spheres.empty()) fail(mjcf_path, "no colliding geom");
  // the skids: the lowest capsules' ends (their bottoms)
  double lowest = 1e9;
  for (const auto& [a, b] : capsules) lowest = std::min({lowest, a.z(), b.z()});
  for (const auto& [a, b] : capsules) {
    if (std::abs(a.z() - lowest) < 1e-6 && std::abs(b.z() - lowest) < 1e-6) {
      out.gear_points_m.push_back(a);
      out.gear_points_m.push_back(b);
    }
  }
  return out;
}

double box_distance_m(const BodyBox& box, const Eigen::Vector3d& p_m) {
  const Eigen::Vector3d d = (p_m - box.centre_m).cwiseAbs() - box.half_m;
  const double outside = d.cwiseMax(0.0).norm();
  return outside > 0.0 ? outside : d.maxCoeff();
}

std::string eight_part(const vision::EightTrack& track, double s_m, double crossing_half_m) {
  const double s = track.wrap_s(s_m);
  const double to_crossing =
      std::min(std::abs(track.delta_s(s, 0.0)), std::abs(track.delta_s(s, 0.5 * track.length_m())));
  if (to_crossing <= crossing_half_m) return "crossing";
  return track.curvature_1_m(s) == 0.0 ? "straight" : "curve";
}

NearMissTracker::NearMissTracker(TruckShape truck, VehicleShape vehicle)
    : truck_(std::move(truck)), vehicle_(std::move(vehicle)) {}

void NearMissTracker::add(const Eigen::Vector3d& vehicle_enu_m,
                          const Eigen::Quaterniond& q_enu_body, const Eigen::Vector3d& truck_enu_m,
                          double truck_yaw_rad) {
  // the vehicle in the truck's frame
  const Eigen::Quaterniond q_enu_truck(Eigen::AngleAxisd(truck_yaw_rad, Eigen::Vector3d::UnitZ()));
  const Eigen::Vector3d p = q_enu_truck.conjugate() * (vehicle_enu_m - truck_enu_m);
  const Eigen::Quaterniond q = (q_enu_truck.conjugate() * q_enu_body).normalized();
  if (last_) {
    for (int k = 1; k < kSubsteps; ++k) {
      const double f = static_cast<double>(k) / kSubsteps;
      score(last_->first + (p - last_->first) * f, last_->second.slerp(f, q));
    }
  }
  score(p, q);
  last_ = std::make_pair(p, q);
  double lowest = 1e9;
  for (const Eigen::Vector3d& g : vehicle_.gear_points_m) lowest = std::min(lowest, (q * g).z());
  latest_ = Relative{p, p.z() + (vehicle_.gear_points_m.empty() ? 0.0 : lowest) -
                            (truck_.deck.centre_m.z() + truck_.deck.half_m.z())};
}

std::optional<double> NearMissTracker::min_clearance_m(const std::string& part) const {
  const auto it = min_part_m_.find(part);
  return it == min_part_m_.end() ? std::nullopt : std::optional<double>(it->second);
}

void NearMissTracker::score(const Eigen::Vector3d& p_truck_m, const Eigen::Quaterniond& q) {
  auto keep_min = [this](const std::string& part, double v) {
    const auto [it, added] = min_part_m_.emplace(part, v);
    if (!added) it->second = std::min(it->second, v);
  };
  // far away: one bounding sphere around the body origin (a lower bound of the clearance)
  if (p_truck_m.norm() > kFar_m) {
    double reach = 0.0;
    for (const auto& s : vehicle_.spheres) reach = std::max(reach, s.centre_m.norm() + s.radius_m);
    for (const BodyBox& b : truck_.parts) keep_min(b.name, box_distance_m(b, p_truck_m) - reach);
    return;
  }
  for (const BodyBox& b : truck_.parts) {
    double d = 1e9;
    for (const auto& s : vehicle_.spheres) {
      d = std::min(d, box_distance_m(b, p_truck_m + q * s.centre_m) - s.radius_m);
    }
    keep_min(b.name, d);
  }
  // the skids at the deck's height: their margin to its edges
  const BodyBox& deck = truck_.deck;
  const double deck_top = deck.centre_m.z() + deck.half_m.z();
  double lowest = 1e9, margin = 1e9;
  for (const Eigen::Vector3d& g : vehicle_.gear_points_m) {
    const Eigen::Vector3d w = p_truck_m + q * g;
    lowest = std::min(lowest, w.z());
    margin = std::min({margin, deck.half_m.x() - std::abs(w.x() - deck.centre_m.x()),
                       deck.half_m.y() - std::abs(w.y() - deck.centre_m.y())});
  }
  // at the deck's height (carried tilted, too) and over it: the centre within the deck's half
  // extents plus kOverDeck_m (beside the truck at that height is no landing)
  const bool at_deck =
      std::abs(lowest - deck_top) <= kAtDeck_m &&
      std::abs(p_truck_m.x() - deck.centre_m.x()) <= deck.half_m.x() + kOverDeck_m &&
      std::abs(p_truck_m.y() - deck.centre_m.y()) <= deck.half_m.y() + kOverDeck_m;
  if (at_deck && (!min_deck_edge_m_ || margin < *min_deck_edge_m_)) min_deck_edge_m_ = margin;
}

}  // namespace uavsim::missions::mbzirc2017
