// Integer key of a root voxel: floor(p / voxel_size) per axis (correct for negative coordinates;
// FAST-LIVO2 truncates there, docs/algorithms.md section 3 [quirk]).
#pragma once

#include "livo/common/so3.hpp"

#include <cmath>
#include <cstddef>
#include <cstdint>

namespace livo {

struct VoxelKey {
  std::int64_t x = 0, y = 0, z = 0;

  /// Key of the voxel [k s, (k+1) s) per axis holding `p`. The caller ensures p is finite and
  /// |p / s| < 2^62 (VoxelMap skips other points).
  static VoxelKey fromPoint(const Vec3& p, double voxel_size) {
    return {static_cast<std::int64_t>(std::floor(p.x() / voxel_size)),
            static_cast<std::int64_t>(std::floor(p.y() / voxel_size)),
            static_cast<std::int64_t>(std::floor(p.z() / voxel_size))};
  }
  /// Metric centre ((k + 0.5) s per axis).
  Vec3 center(double voxel_size) const {
    return Vec3((static_cast<double>(x) + 0.5) * voxel_size, (static_cast<double>(y) + 0.5) * voxel_size,
                (static_cast<double>(z) + 0.5) * voxel_size);
  }
  bool operator==(const VoxelKey& o) const { return x == o.x && y == o.y && z == o.z; }
  bool operator!=(const VoxelKey& o) const { return !(*this == o); }
};

/// Hash: splitmix64 finaliser applied after folding in each coordinate, so neighbouring keys spread
/// over all buckets and no linear combination of coordinates collides systematically.
struct VoxelKeyHash {
  static std::uint64_t mix(std::uint64_t h) noexcept {
    h ^= h >> 30;
    h *= 0xBF58476D1CE4E5B9ull;
    h ^= h >> 27;
    h *= 0x94D049BB133111EBull;
    h ^= h >> 31;
    return h;
  }
  std::size_t operator()(const VoxelKey& k) const noexcept {
    std::uint64_t h = mix(static_cast<std::uint64_t>(k.x) + 0x9E3779B97F4A7C15ull);
    h = mix(h ^ static_cast<std::uint64_t>(k.y));
    h = mix(h ^ static_cast<std::uint64_t>(k.z));
    return static_cast<std::size_t>(h);
  }
};

}  // namespace livo
