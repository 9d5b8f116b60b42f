// The hybrid map's local LiDAR plane map: the voxel plane map (VoxelMap) and, in hybrid mode, the
// index of its root voxels by tile (RootTileIndex, hybrid_map_tiles.hpp) that slides and evictions
// use to find root voxels without a full hash scan.
//
// Pointers: Plane* from voxels().findBestPlane stay valid until the next modification: insert(),
// removeRoot(), removeRootsOf(), load() or clear() (through HybridMap: insertion, update(), clear(),
// loading a map file).
// Thread safety: const member functions may run concurrently; everything else needs exclusive access.
#pragma once

#include "livo/map/hybrid_map_tiles.hpp"
#include "livo/map/voxel_map.hpp"

#include <cstddef>
#include <istream>
#include <vector>

namespace livo {

class LocalLidarMap {
 public:
  /// `index_roots`: keep the tile index up to date on insertion (hybrid mode); `tile_voxels`: root
  /// voxels per tile edge (>= 1).
  LocalLidarMap(VoxelMapConfig config, bool index_roots, int tile_voxels);

  /// Inserts world points (VoxelMap::insert) and, when indexing, records their new root voxels in the
  /// tile index. Returns the number of points taken.
  std::size_t insert(const std::vector<PointWithCov>& points);
  const VoxelMap& voxels() const { return voxels_; }
  const RootTileIndex& tiles() const { return tiles_; }
  /// Points taken by insert() since construction (never reset, not even by clear(); the byte
  /// estimate's growth term).
  std::size_t insertedPoints() const { return inserted_points_; }

  /// Eviction: drops one root voxel and its index entry; false when it did not exist.
  bool removeRoot(const VoxelKey& key);
  /// Slide step on one index tile: removes its root voxels whose centre `leaves(centre)` says must go,
  /// at most `limit` of them. `done` tells whether the tile is finished (then its record is dropped
  /// when empty); an unknown tile is finished at once. Returns the count removed.
  template <class Leaves>
  std::size_t removeRootsOf(const VoxelKey& tile, Leaves&& leaves, std::size_t limit, bool& done);

  /// Replaces the content with a saved VoxelMap (VoxelMap::load; throws likewise) and indexes every
  /// root voxel (in either mode).
  void load(std::istream& is);
  void clear();

 private:
  VoxelMap voxels_;
  RootTileIndex tiles_;
  bool index_roots_;
  std::size_t inserted_points_ = 0;
  std::vector<PointWithCov> scratch_;  ///< one-point batch for insert
};

template <class Leaves>
std::size_t LocalLidarMap::removeRootsOf(const VoxelKey& tile, Leaves&& leaves, std::size_t limit, bool& done) {
  RootTileIndex::RootSet* roots = tiles_.roots(tile);
  done = true;
  if (roots == nullptr) return 0;
  const double s = voxels_.config().voxel_size_m;
  std::size_t removed = 0;
  auto it = roots->begin();
  while (it != roots->end()) {
    if (!leaves(it->center(s))) {
      ++it;
      continue;
    }
    if (removed == limit) break;
    voxels_.removeVoxel(*it);
    it = roots->erase(it);
    ++removed;
  }
  done = it == roots->end();
  tiles_.noteRemoved(removed);
  if (done) tiles_.dropIfEmpty(tile);
  return removed;
}

}  // namespace livo
