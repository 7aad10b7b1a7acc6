#include "app/recording.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <deque>
#include <set>
#include <stdexcept>
#include <utility>

#include "uavsim/common/pinhole.hpp"

namespace uavsim::server::app {

// which camera --record films: the named camera, else (overview, follow, top) the world camera
// "overview", else the first world camera, else the first
std::optional<size_t> record_camera(const std::vector<render::CameraSetup>& cameras,
                                    const std::string& choice) {
  const bool directed = choice == "follow" || choice == "top" || choice.rfind("follow:", 0) == 0;
  if (!directed && choice != "overview") {
    for (size_t i = 0; i < cameras.size(); ++i) {
      if (cameras[i].config.camera == choice) return i;
    }
    return std::nullopt;
  }
  for (size_t i = 0; i < cameras.size(); ++i) {
    if (cameras[i].config.camera == "overview") return i;
  }
  for (size_t i = 0; i < cameras.size(); ++i) {
    if (cameras[i].vehicle < 0) return i;
  }
  if (!cameras.empty()) return 0;
  return std::nullopt;
}

// the director of --record-camera follow|follow:NAME|top (null for a camera posed by the model);
// throws std::invalid_argument for a vehicle name the world does not have
std::shared_ptr<render::CameraDirector> record_director(const std::string& choice,
                                                        const render::FrameCamera& cam,
                                                        const sim::Simulation& s) {
  render::DirectorParams p;
  if (choice == "top") {
    p.mode = render::DirectorMode::kTop;
  } else if (choice.rfind("follow", 0) == 0 && (choice.size() == 6 || choice[6] == ':')) {
    p.mode = render::DirectorMode::kFollow;
    if (choice.size() > 7) {
      const std::string name = choice.substr(7);
      for (size_t i = 0; i < s.vehicle_count(); ++i) {
        if (s.vehicle_name(i) == name) p.vehicle = static_cast<int>(i);
      }
      if (!p.vehicle)
        throw std::invalid_argument("--record-camera " + choice + ": the world has no vehicle " +
                                    name);
    }
  } else {
    return nullptr;
  }
  p.fovy_deg = common::PinholeIntrinsics::fovy_deg_of(cam.height_px, cam.fy_px);
  p.aspect = static_cast<double>(cam.width_px) / cam.height_px;
  return std::make_shared<render::CameraDirector>(p);
}

// the overlay of a recorded frame: the loop thread's view at that instant, with what it keeps
// between frames (trails, the places of events); notes: the launchers' counters and notes
std::function<render::OverlayInfo()> record_overlay_source(sim::Simulation& s,
                                                           const objects::ObjectSet& objects,
                                                           const RunReporter& reporter,
                                                           const api::OverlayOps& notes) {
  constexpr double kEventShownS = 4.0;
  constexpr size_t kEventLines = 5;
  constexpr double kTrailS = 10.0;
  struct Memory {
    uint64_t events_seen = 0;  // the seq of the next event to mark
    int pops = 0;
    std::vector<render::OverlayMarker> markers;
    std::set<int> killed;  // vehicles killed (their crash is not marked again)
    std::vector<std::deque<std::pair<double, Eigen::Vector3d>>> trails;
  };
  auto memory = std::make_shared<Memory>();
  return [&s, &reporter, &notes, memory, balloons = objects.balloons,
          trucks = !objects.trucks.empty()] {
    render::OverlayInfo info;
    info.time_s = s.time_s();
    const sim::EventLog& log = s.events();
    const std::deque<sim::Event>& all = log.recent();
    Memory& mem = *memory;
    if (log.next_seq() < mem.events_seen) *memory = Memory{};  // a reset: the run starts afresh
    for (size_t i = 0; i < s.vehicle_count(); ++i) {
      info.vehicles.push_back(
          {s.vehicle_name(i), s.runtime(i).crashed ? "CRASHED" : fc::mode_name(s.fc(i).mode())});
    }

    // trails: the last kTrailS seconds of each vehicle's positions, at the frames' instants
    mem.trails.resize(s.vehicle_count());
    for (size_t i = 0; i < s.vehicle_count(); ++i) {
      auto& trail = mem.trails[i];
      if (!trail.empty() && trail.back().first > info.time_s) trail.clear();
      trail.emplace_back(info.time_s, s.truth(i).position_enu_m);
      while (trail.front().first < info.time_s - kTrailS) trail.pop_front();
      info.trails_enu_m.emplace_back();
      for (const auto& [t, p] : trail) info.trails_enu_m.back().push_back(p);
    }

    // the places of what happened: where the vehicle is when the event is first seen (within a
    // frame period of it)
    for (const sim::Event& e : all) {
      if (e.seq < mem.events_seen) continue;
      if (e.vehicle < 0 || static_cast<size_t>(e.vehicle) >= s.vehicle_count()) continue;
      std::string what;
      if (e.type == sim::EventType::kBalloonPopped) {
        what = "pop " + std::to_string(++mem.pops);
      } else if (e.type == sim::EventType::kLandedOnTarget) {
        what = "landed";
      } else if (e.type == sim::EventType::kCrash) {
        if (mem.killed.count(e.vehicle) != 0) continue;  // a kill's consequence: marked already
        what = "crash";
      } else if (e.type == sim::EventType::kVehicleKilled) {
        mem.killed.insert(e.vehicle);
        what = "killed";
      } else {
        continue;
      }
      mem.markers.push_back({s.truth(static_cast<size_t>(e.vehicle)).position_enu_m, e.vehicle,
                             s.vehicle_name(static_cast<size_t>(e.vehicle)) + " " + what});
    }
    mem.events_seen = log.next_seq();
    info.markers = mem.markers;

    // the recent events worth a line (a vehicle's own mode shows beside it)
    auto line = [&](double t_s, int vehicle, const std::string& what) {
      char t[24];
      std::snprintf(t, sizeof(t), "%.1f s ", t_s);
      std::string text = t;
      if (vehicle >= 0 && static_cast<size_t>(vehicle) < s.vehicle_count()) {
        text += s.vehicle_name(static_cast<size_t>(vehicle)) + " ";
      } else {
        vehicle = -1;
      }
      return render::OverlayLine{text + what, vehicle};
    };
    for (auto it = all.rbegin(); it != all.rend() && info.events.size() < kEventLines; ++it) {
      if (it->time_s < info.time_s - kEventShownS) break;
      if (it->type == sim::EventType::kModeChange || it->type == sim::EventType::kArmed ||
          it->type == sim::EventType::kDisarmed) {
        continue;
      }
      std::string what = sim::event_type_name(it->type);
      if (!it->detail.empty()) what += " " + it->detail.substr(0, 40);
      info.events.insert(info.events.begin(), line(it->time_s, it->vehicle, what));
    }
    // the failsafes the flight controllers announced and the launchers' notes, newest last
    std::vector<std::pair<double, render::OverlayLine>> extra;
    for (const ReportedEvent& f : reporter.recent_failsafes()) {
      if (f.time_s < info.time_s - kEventShownS || f.time_s > info.time_s) continue;
      extra.emplace_back(f.time_s, line(f.time_s, f.vehicle, "FAILSAFE " + f.detail.substr(0, 40)));
    }
    for (const api::OverlayNote& n : notes.notes()) {
      if (n.time_s < info.time_s - kEventShownS || n.time_s > info.time_s) continue;
      extra.emplace_back(n.time_s, line(n.time_s, n.vehicle, n.text));
    }
    std::stable_sort(extra.begin(), extra.end(),
                     [](const auto& a, const auto& b) { return a.first < b.first; });
    for (auto& [t, l] : extra) {
      info.events.push_back(std::move(l));
      if (info.events.size() > kEventLines) info.events.erase(info.events.begin());
    }
    if (balloons != nullptr) {
      info.counters.push_back("balloons popped " + std::to_string(balloons->popped_count()) + "/" +
                              std::to_string(balloons->balloons().size()));
    }
    if (trucks) {
      info.counters.push_back("landed on target " +
                              std::to_string(s.events().count(sim::EventType::kLandedOnTarget)));
    }
    for (const std::string& c : notes.counters()) info.counters.push_back(c);
    return info;
  };
}

}  // namespace uavsim::server::app
