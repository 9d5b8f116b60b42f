// Undistortion lookup tables for any CameraModel (pinhole-radtan and fisheye alike; FAST-LIVO2's
// Equidistant camera has none, which crashes its COLMAP export, docs/algorithms.md §8 #246).
//
// For every pixel (u, v) of an ideal, distortion-free pinhole image, the table holds the pixel of the real
// camera that sees the same ray: bearing ~ (( u - cx) / fx, (v - cy) / fy, 1), px = camera.project(bearing).
// The tables are the map_x / map_y of cv::remap (CV_32FC1, row-major), i.e. the same thing
// cv::initUndistortRectifyMap builds with R = I; no OpenCV is needed to build them.
#pragma once

#include "livo/sensors/camera_model.hpp"

#include <vector>

namespace livo {

/// A distortion-free pinhole image (pixel-centre convention of camera_model.hpp).
struct IdealPinhole {
  int width = 0, height = 0;             ///< pixels
  double fx = 0, fy = 0, cx = 0, cy = 0;  ///< pixels
  /// The same size and intrinsics as `camera` (distortion dropped).
  static IdealPinhole sameAs(const CameraModel& camera);
};

struct UndistortionMap {
  int width = 0, height = 0;     ///< of the ideal image
  std::vector<float> map_x, map_y;  ///< width * height each, row-major; -1 where the ray is not valid
  int invalid = 0;                  ///< number of entries set to -1
};

/// Throws std::invalid_argument on a non-positive size or focal length.
UndistortionMap buildUndistortionMap(const CameraModel& camera, const IdealPinhole& ideal);

}  // namespace livo
