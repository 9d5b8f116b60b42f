#include "livo/viewer/screenshot.hpp"

#include <cstdio>
#include <filesystem>

namespace livo::viewer {

std::string screenshotJson(const ScreenshotInfo& info) {
  char buf[128];
  std::string m;
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) {
      std::snprintf(buf, sizeof buf, "%s%.17g", (r || c) ? ", " : "", info.world_to_ndc(r, c));
      m += buf;
    }
  std::snprintf(buf, sizeof buf, "%.6f", info.message_time_s);
  return "{\"width\": " + std::to_string(info.width) + ", \"height\": " + std::to_string(info.height) +
         ", \"world_to_ndc\": [" + m + "], \"view\": \"" + info.view + "\", \"colour\": \"" + info.colour +
         "\", \"poses\": " + std::to_string(info.poses) + ", \"map_points\": " + std::to_string(info.map_points) +
         ", \"first_utime\": " + std::to_string(info.first_utime) + ", \"last_utime\": " +
         std::to_string(info.last_utime) + ", \"message_time_s\": " + buf + "}\n";
}

std::string sidecarPath(const std::string& png_path) {
  return std::filesystem::path(png_path).replace_extension(".json").string();
}

}  // namespace livo::viewer
