// Tile index of the LiDAR root voxels, for incremental sliding and eviction of the hybrid map.
//
// VoxelMap keeps its root voxels in one hash; a slide there (removeOutsideBox) is a full hash scan plus
// all erasures in one call: ~10 ms for a 20 m slide of a 200 m street map of 32k root voxels, and the
// erasures alone cost ~2.5 us per root voxel (test_map_hybrid, SlideTimeOnALargeStreetMap). This index
// groups the root keys by tile (tile_voxels^3 root voxels per tile), so that a slide only visits the
// tiles that reach out of the new cube, and the erasures can be spread over several updates.
#pragma once

#include "livo/map/voxel_key.hpp"

#include <cstddef>
#include <unordered_map>
#include <unordered_set>
#include <vector>

namespace livo {

class RootTileIndex {
 public:
  using RootSet = std::unordered_set<VoxelKey, VoxelKeyHash>;

  /// `voxel_size_m`: the root voxel edge; `tile_voxels`: root voxels per tile edge (>= 1).
  RootTileIndex(double voxel_size_m, int tile_voxels);

  /// Records a root key (idempotent). Consecutive calls with the same key cost one comparison.
  void add(const VoxelKey& root);
  /// Forgets a root key; returns true when it was recorded.
  bool remove(const VoxelKey& root);
  void clear();

  std::size_t size() const { return count_; }
  std::size_t numTiles() const { return tiles_.size(); }
  VoxelKey tileOf(const VoxelKey& root) const;
  /// Tiles holding a root whose centre may lie outside the cube of half edge `half_edge_m` around
  /// `center` (same criterion as VoxelMap::removeOutsideBox: |c_i - center_i| > half_edge on some
  /// axis). Tiles entirely inside are skipped without looking at their roots.
  std::vector<VoxelKey> tilesReachingOutside(const Vec3& center, double half_edge_m) const;
  /// The roots of a tile (null when the tile is empty / unknown).
  RootSet* roots(const VoxelKey& tile);
  /// Drops a tile record when it holds no roots.
  void dropIfEmpty(const VoxelKey& tile);

  template <class F>
  void forEachRoot(F&& f) const {
    for (const auto& kv : tiles_)
      for (const VoxelKey& k : kv.second) f(k);
  }
  /// Same accounting as VoxelMap::bytes(): buckets, nodes and 16 bytes of allocator overhead per block.
  std::size_t bytes() const;

  /// Called by the owner after erasing from a tile's RootSet directly.
  void noteRemoved(std::size_t n) {
    count_ -= n;
    have_last_root_ = false;  // the cached root may be among them
  }

 private:
  double voxel_size_m_;
  std::int64_t tile_voxels_;
  std::unordered_map<VoxelKey, RootSet, VoxelKeyHash> tiles_;
  std::size_t count_ = 0;
  // One-entry caches for add(): scan points arrive in runs that share a voxel / a tile.
  VoxelKey last_root_, last_tile_;
  RootSet* last_set_ = nullptr;
  bool have_last_root_ = false;
};

}  // namespace livo
