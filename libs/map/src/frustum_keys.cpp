#include "livo/map/frustum_keys.hpp"

#include "livo/map/plane_finder.hpp"
#include "livo/sensors/camera_model.hpp"

#include <algorithm>
#include <cmath>
#include <tuple>

namespace livo {

std::vector<VoxelKey> frustumVoxelKeys(const CameraModel& cam, const Pose& T_world_camera, double voxel_size_m,
                                       int cell_px, double min_depth_m, double max_depth_m) {
  std::vector<VoxelKey> keys;
  if (!(voxel_size_m > 0) || cell_px < 1 || !(max_depth_m > min_depth_m) || !(min_depth_m >= 0)) return keys;
  const double step = 0.5 * voxel_size_m;
  const Vec3 c = T_world_camera.translation();
  for (int y = cell_px / 2; y < cam.height(); y += cell_px) {
    for (int x = cell_px / 2; x < cam.width(); x += cell_px) {
      Vec3 bearing;
      if (!cam.unproject(Eigen::Vector2d(x, y), bearing) || !(bearing.z() > 1e-6)) continue;
      const Vec3 ray = T_world_camera.linear() * (bearing / bearing.z());  // unit depth along the axis
      for (double d = std::max(min_depth_m, step); d <= max_depth_m; d += step) {
        const Vec3 p = c + d * ray;
        if (keyablePoint(p, voxel_size_m)) keys.push_back(VoxelKey::fromPoint(p, voxel_size_m));
      }
    }
  }
  std::sort(keys.begin(), keys.end(), [](const VoxelKey& a, const VoxelKey& b) {
    return std::tie(a.x, a.y, a.z) < std::tie(b.x, b.y, b.z);
  });
  keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
  return keys;
}

}  // namespace livo
