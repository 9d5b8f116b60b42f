// The sidecar of a screenshot (out.png -> out.json): what the picture shows and the camera that took
// it, so that a test (or a user) can project world points into the picture:
//   pixel column = (ndc_x + 1) / 2 * width, row (from the top) = (1 - ndc_y) / 2 * height,
//   with ndc = world_to_ndc * [x y z 1], divided by its 4th component.
#pragma once

#include "livo/common/types.hpp"

#include <Eigen/Core>

#include <string>

namespace livo::viewer {

struct ScreenshotInfo {
  int width = 0, height = 0;
  Eigen::Matrix4d world_to_ndc = Eigen::Matrix4d::Identity();  ///< view + projection of the camera
  std::string view, colour;
  std::size_t poses = 0, map_points = 0;
  Utime first_utime = 0, last_utime = 0;  ///< the drawn trajectory's time span
  double message_time_s = 0.0;            ///< elapsed message time when taken
};

/// One JSON object (keys as in ScreenshotInfo; world_to_ndc row-major, 16 numbers).
std::string screenshotJson(const ScreenshotInfo& info);
/// "out.png" -> "out.json" (any extension replaced; none: appended).
std::string sidecarPath(const std::string& png_path);

}  // namespace livo::viewer
