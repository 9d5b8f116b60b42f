// Hybrid map (docs/algorithms.md "The two ideas", 3; sections 3 "Sliding" and 8 "Memory"), composed of
// parts a reader can name:
//   - lidar():  the local LiDAR plane map and its root tile index (local_lidar_map.hpp);
//   - visual(): the local and long-term visual maps, searched together, and the map server's side of
//               the visual points (dual_visual_map.hpp);
//   - update(): the per-frame maintenance: the slides of the local and long-term cubes
//               (slide_policy.hpp), then the memory cap (memory_cap.hpp), within
//               max_removals_per_update items per call (evictions first);
//   - stats() / bytesEstimate(): the byte model, an exact walk and an O(1) estimate
//               (byte_accounting.hpp);
//   - persistence: map files (map_file.hpp).
// hybrid mode: the local map (LiDAR planes and local visual points) is bounded by a cube around the
// robot, the long-term visual map by a larger one, and the accounted bytes by the memory cap.
// global mode (FAST-LIVO2 behaviour): one unbounded LiDAR map and one visual map; update() does nothing.
//
// Pointers: Plane* (lidar().voxels().findBestPlane) stay valid until the next LiDAR insertion,
// update(), clear() or map file load; VisualPoint* (visual().retrieve / find) until that point
// leaves its map: visual().removeBadPoints() or upsert(), update(), clear() or a map file load
// (details in the parts' headers).
// Thread safety: const member functions may run concurrently; everything else needs exclusive access.
#pragma once

#include "livo/map/byte_accounting.hpp"
#include "livo/map/dual_visual_map.hpp"
#include "livo/map/hybrid_map_config.hpp"
#include "livo/map/local_lidar_map.hpp"
#include "livo/map/map_maintenance.hpp"
#include "livo/map/memory_cap.hpp"
#include "livo/map/slide_policy.hpp"
#include "livo/map/visual_map.hpp"
#include "livo/map/voxel_map.hpp"

#include <cstddef>

namespace livo {

class HybridMap {
 public:
  HybridMap(HybridMapConfig config, VoxelMapConfig lidar_config, VisualMapConfig visual_config);

  // --- The parts ----------------------------------------------------------------------------------
  /// LiDAR insertion (lidar().insert) and the plane map (lidar().voxels()).
  LocalLidarMap& lidar() { return lidar_; }
  const LocalLidarMap& lidar() const { return lidar_; }
  /// The per-frame visual operations over both visual maps, the protocol operations on visual points
  /// and the two maps (visual().local(), visual().longterm()).
  DualVisualMap& visual() { return visual_; }
  const DualVisualMap& visual() const { return visual_; }
  /// Cube centres and pending slide work (changed by update(), finishPendingWork() and clear()).
  const SlidePolicy& slides() const { return slides_; }

  // --- Maintenance ----------------------------------------------------------------------------------
  /// Once per frame, after the map insertions: starts a slide when due (local, long-term), does up
  /// to max_removals_per_update items of pending work (evictions, then slide work), then checks the
  /// memory cap: over its high-water mark it plans an eviction and starts it with what is left of
  /// the budget; over the cap itself it evicts beyond the budget until under it, so that the
  /// accounted bytes (estimate) are under the cap after every call whenever the cap can hold
  /// anything. The first call centres both cubes (counted as a slide). Hybrid mode only; global mode
  /// returns at once. Non-finite positions are ignored. Invalidates handed-out pointers (see above).
  MapUpdateReport update(const Vec3& robot_position);
  /// Finishes all pending slide work and evictions now (e.g. before an exact comparison in a test).
  void finishPendingWork();
  const HybridMapCounters& counters() const { return counters_; }
  /// Changes the memory cap (MiB, 0 = none; e.g. a map server's --memory-cap-mb); applied by the next
  /// update(). Throws std::invalid_argument on a negative or non-finite value.
  void setMemoryCapMb(double mb);
  /// The content changed outside update() (e.g. a map file was loaded): with a cap, the next update()
  /// makes an exact byte count.
  void requestExactCount() { cap_.requestExactCount(); }

  // --- Bytes ----------------------------------------------------------------------------------------
  /// Exact counts and bytes: walks every structure (stats rate, not per frame).
  HybridMapStats stats() const;
  std::size_t bytes() const { return stats().bytes; }
  /// O(1) estimate (ByteAccounting::estimate).
  std::size_t bytesEstimate() const { return bytes_.estimate(lidar_, visual_); }

  const HybridMapConfig& config() const { return cfg_; }
  MapMode mode() const { return cfg_.mode; }
  /// Empties every part (counters and the byte model's calibration are kept).
  void clear();

 private:
  std::size_t workBytes() const { return slides_.workBytes() + cap_.workBytes(); }

  HybridMapConfig cfg_;
  LocalLidarMap lidar_;
  DualVisualMap visual_;
  SlidePolicy slides_;
  MemoryCap cap_;
  ByteAccounting bytes_;
  HybridMapCounters counters_;
};

}  // namespace livo
