#include "app/render_cameras_option.hpp"

#include <algorithm>
#include <sstream>

#include "uavsim/common/parse_number.hpp"

namespace uavsim::server::app {

bool parse_render_cameras(const std::string& text, std::vector<RenderCamera>* cameras,
                          std::string* why) {
  const std::string usage = "--render-cameras needs CAMERA[:rgb|grey|depth|segmentation][@FPS],...";
  if (text.empty()) {
    *why = usage + ", got ''";
    return false;
  }
  std::istringstream list(text);
  std::string entry;
  std::vector<RenderCamera> parsed;
  // getline drops a trailing empty entry ("a,"): refuse it by counting the commas
  const auto commas = static_cast<std::size_t>(std::count(text.begin(), text.end(), ','));
  while (std::getline(list, entry, ',')) {
    RenderCamera c;
    std::string name = entry;
    if (const auto at = name.find('@'); at != std::string::npos) {
      const std::string fps_text = name.substr(at + 1);
      double fps = 0.0;
      if (!common::parse_double(fps_text.c_str(), kMinRenderFps, kMaxRenderFps, &fps)) {
        std::ostringstream m;
        m << "--render-cameras: '" << entry << "': FPS needs frames per sim second from "
          << kMinRenderFps << " to " << kMaxRenderFps;
        *why = m.str();
        return false;
      }
      c.fps_hz = fps;
      name.resize(at);
    }
    if (const auto colon = name.find(':'); colon != std::string::npos) {
      c.format = name.substr(colon + 1);
      name.resize(colon);
    }
    const bool format_ok = c.format == "rgb" || c.format == "grey" || c.format == "depth" ||
                           c.format == "segmentation";
    if (name.empty() || !format_ok) {
      *why = usage + ", got '" + entry + "'";
      return false;
    }
    c.camera = name;
    parsed.push_back(std::move(c));
  }
  if (parsed.size() != commas + 1) {
    *why = usage + ", got '" + text + "' (an empty entry)";
    return false;
  }
  // each camera once, with one format and one rate
  for (const RenderCamera& c : parsed) {
    const auto same = [&c](const RenderCamera& o) { return o.camera == c.camera; };
    if (std::count_if(parsed.begin(), parsed.end(), same) > 1 ||
        std::any_of(cameras->begin(), cameras->end(), same)) {
      *why = "--render-cameras: camera '" + c.camera + "' named twice";
      return false;
    }
  }
  cameras->insert(cameras->end(), parsed.begin(), parsed.end());
  return true;
}

}  // namespace uavsim::server::app
