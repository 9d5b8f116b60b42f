// Undistortion tables: ideal pinhole pixel -> ray -> real camera pixel (camera_model_undistort.hpp).
#include "livo/sensors/camera_model_undistort.hpp"

#include <cmath>
#include <stdexcept>

namespace livo {

IdealPinhole IdealPinhole::sameAs(const CameraModel& camera) {
  IdealPinhole p;
  p.width = camera.width(), p.height = camera.height();
  p.fx = camera.fx(), p.fy = camera.fy(), p.cx = camera.cx(), p.cy = camera.cy();
  return p;
}

UndistortionMap buildUndistortionMap(const CameraModel& camera, const IdealPinhole& ideal) {
  if (ideal.width <= 0 || ideal.height <= 0)
    throw std::invalid_argument("buildUndistortionMap: ideal image size must be positive");
  if (!(ideal.fx > 0) || !(ideal.fy > 0))
    throw std::invalid_argument("buildUndistortionMap: ideal fx, fy must be > 0");
  UndistortionMap m;
  m.width = ideal.width, m.height = ideal.height;
  const size_t n = static_cast<size_t>(ideal.width) * ideal.height;
  m.map_x.resize(n), m.map_y.resize(n);
  Eigen::Vector2d px;
  for (int v = 0; v < ideal.height; ++v) {
    const double y = (v - ideal.cy) / ideal.fy;
    for (int u = 0; u < ideal.width; ++u) {
      const size_t i = static_cast<size_t>(v) * ideal.width + u;
      if (camera.project(Eigen::Vector3d((u - ideal.cx) / ideal.fx, y, 1.0), px)) {
        m.map_x[i] = static_cast<float>(px.x());
        m.map_y[i] = static_cast<float>(px.y());
      } else {
        m.map_x[i] = m.map_y[i] = -1.0f;
        ++m.invalid;
      }
    }
  }
  return m;
}

}  // namespace livo
