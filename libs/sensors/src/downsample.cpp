#include "livo/sensors/downsample.hpp"

#include <cmath>
#include <cstdint>

namespace livo {

namespace {

struct VoxelIndex {
  std::int32_t x, y, z;
  bool operator==(const VoxelIndex& o) const { return x == o.x && y == o.y && z == o.z; }
};

std::uint64_t hashVoxel(const VoxelIndex& k) {
  std::uint64_t h = static_cast<std::uint32_t>(k.x) * 0x9E3779B97F4A7C15ull;
  h ^= static_cast<std::uint32_t>(k.y) * 0xC2B2AE3D27D4EB4Full;
  h ^= static_cast<std::uint32_t>(k.z) * 0x165667B19E3779F9ull;
  h ^= h >> 29;
  h *= 0xBF58476D1CE4E5B9ull;
  h ^= h >> 32;
  return h;
}

/// voxel_of[i] = voxel id of point i in first-appearance order, -1 for skipped points.
/// Returns the number of voxels.
template <class PositionOf>
int assignVoxels(std::size_t n, PositionOf position_of, double leaf, std::vector<int>& voxel_of) {
  voxel_of.assign(n, -1);
  std::size_t table_size = 16;
  while (table_size < 2 * n) table_size <<= 1;
  const std::uint64_t mask = table_size - 1;
  std::vector<int> table(table_size, -1);  // voxel id per slot, -1 empty
  std::vector<VoxelIndex> keys;
  keys.reserve(n / 4 + 16);
  const double inv_leaf = 1.0 / leaf;
  const double limit = 1073741824.0;  // 2^30 leaves

  for (std::size_t i = 0; i < n; ++i) {
    const Eigen::Vector3d p = position_of(i);
    const double fx = std::floor(p.x() * inv_leaf), fy = std::floor(p.y() * inv_leaf),
                 fz = std::floor(p.z() * inv_leaf);
    // The negated comparisons also reject NaN.
    if (!(std::abs(fx) < limit && std::abs(fy) < limit && std::abs(fz) < limit)) continue;
    const VoxelIndex key{static_cast<std::int32_t>(fx), static_cast<std::int32_t>(fy),
                         static_cast<std::int32_t>(fz)};
    std::uint64_t slot = hashVoxel(key) & mask;
    for (;;) {
      const int id = table[slot];
      if (id < 0) {
        table[slot] = static_cast<int>(keys.size());
        voxel_of[i] = static_cast<int>(keys.size());
        keys.push_back(key);
        break;
      }
      if (keys[id] == key) {
        voxel_of[i] = id;
        break;
      }
      slot = (slot + 1) & mask;
    }
  }
  return static_cast<int>(keys.size());
}

}  // namespace

std::vector<LidarPoint> voxelDownsample(const std::vector<LidarPoint>& points, float leaf_m) {
  if (!(leaf_m > 0.f) || !std::isfinite(leaf_m)) return points;
  std::vector<int> voxel_of;
  const int n_voxels = assignVoxels(
      points.size(), [&](std::size_t i) { return Eigen::Vector3d(points[i].p_lidar.cast<double>()); },
      static_cast<double>(leaf_m), voxel_of);

  struct Sum {
    Eigen::Vector3d p = Eigen::Vector3d::Zero();
    double t = 0.0, intensity = 0.0;
    int count = 0;
    std::int16_t ring = -1;
  };
  std::vector<Sum> sums(n_voxels);
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (voxel_of[i] < 0) continue;
    Sum& s = sums[voxel_of[i]];
    const LidarPoint& q = points[i];
    if (s.count == 0) s.ring = q.ring;
    s.p += q.p_lidar.cast<double>();
    s.t += q.time_offset_s;
    s.intensity += q.intensity;
    ++s.count;
  }
  std::vector<LidarPoint> out(n_voxels);
  for (int v = 0; v < n_voxels; ++v) {
    const double inv = 1.0 / sums[v].count;
    out[v].p_lidar = (sums[v].p * inv).cast<float>();
    out[v].time_offset_s = static_cast<float>(sums[v].t * inv);
    out[v].intensity = static_cast<float>(sums[v].intensity * inv);
    out[v].ring = sums[v].ring;
  }
  return out;
}

std::vector<Eigen::Vector3d> voxelDownsample(const std::vector<Eigen::Vector3d>& points, double leaf_m) {
  if (!(leaf_m > 0.0) || !std::isfinite(leaf_m)) return points;
  std::vector<int> voxel_of;
  const int n_voxels = assignVoxels(points.size(), [&](std::size_t i) { return points[i]; }, leaf_m, voxel_of);
  std::vector<Eigen::Vector3d> sum(n_voxels, Eigen::Vector3d::Zero());
  std::vector<int> count(n_voxels, 0);
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (voxel_of[i] < 0) continue;
    sum[voxel_of[i]] += points[i];
    ++count[voxel_of[i]];
  }
  for (int v = 0; v < n_voxels; ++v) sum[v] /= count[v];
  return sum;
}

}  // namespace livo
