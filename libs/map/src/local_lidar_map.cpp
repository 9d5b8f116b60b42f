// LocalLidarMap: insertion with root indexing, root removal for slides and evictions, reloading.
#include "livo/map/local_lidar_map.hpp"

namespace livo {

LocalLidarMap::LocalLidarMap(VoxelMapConfig config, bool index_roots, int tile_voxels)
    : voxels_(config), tiles_(config.voxel_size_m, tile_voxels), index_roots_(index_roots) {}

std::size_t LocalLidarMap::insert(const std::vector<PointWithCov>& points) {
  if (!index_roots_) {
    const std::size_t taken = voxels_.insert(points);
    inserted_points_ += taken;
    return taken;
  }
  // One point at a time, in the same order, so that a new root voxel is seen (the root count grows)
  // and only new roots go into the tile index: indexing every point cost ~0.4 us per point.
  std::size_t taken = 0;
  scratch_.resize(1);
  for (const PointWithCov& pw : points) {
    scratch_[0] = pw;
    const std::size_t roots_before = voxels_.numRootVoxels();
    taken += voxels_.insert(scratch_);
    if (voxels_.numRootVoxels() != roots_before) tiles_.add(voxels_.keyOf(pw.p_world));
  }
  inserted_points_ += taken;
  return taken;
}

bool LocalLidarMap::removeRoot(const VoxelKey& key) {
  if (voxels_.removeVoxel(key) == 0) return false;
  tiles_.remove(key);
  return true;
}

void LocalLidarMap::load(std::istream& is) {
  voxels_.load(is);
  voxels_.forEachRoot([this](const VoxelKey& k) { tiles_.add(k); });
}

void LocalLidarMap::clear() {
  voxels_.clear();
  tiles_.clear();
}

}  // namespace livo
