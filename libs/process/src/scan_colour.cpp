#include "livo/process/scan_colour.hpp"

#include "livo/map/visual_point.hpp"

#include <cmath>

namespace livo {

RegisteredScan colourScan(Utime t, const Pose& T_world_imu, const std::vector<BodyPoint>& points,
                          const CameraModel* cam, const Image* image, const Pose& T_imu_camera, double scale) {
  RegisteredScan s;
  s.utime = t;
  const bool colour = cam != nullptr && image != nullptr && !image->data.empty();
  const Pose T_camera_world = (T_world_imu * T_imu_camera).inverse();
  s.points.reserve(points.size());
  s.intensity.reserve(points.size());
  if (colour) s.rgb.reserve(points.size());
  for (const auto& bp : points) {
    const Vec3 p_w = T_world_imu * bp.p_imu;
    s.points.push_back(p_w.cast<float>());
    s.intensity.push_back(1.f);
    if (!colour) continue;
    std::int32_t c = -1;
    Vec2 px;
    float g = 0.f;
    if (cam->project(T_camera_world * p_w, px) && cam->inImage(px, 1.0) &&
        sampleBilinear(*image, (px.x() + 0.5) / scale - 0.5, (px.y() + 0.5) / scale - 0.5, g)) {
      const auto v = static_cast<std::int32_t>(std::lround(g));
      c = (v << 16) | (v << 8) | v;
    }
    s.rgb.push_back(c);
  }
  return s;
}

}  // namespace livo
