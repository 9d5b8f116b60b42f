// Byte model of the hybrid map (docs/algorithms.md section 8, "Memory"): the exact count, a walk of every
// structure (LiDAR octrees, both visual maps, the tile index and the maintenance's work lists), and the
// O(1) estimate the memory cap is checked on between exact counts: counts times the bytes per item of
// the last exact count (or defaults), plus the growth since that count (inserted LiDAR points times a
// learnt rate, added visual observations). Each exact count made through recount() calibrates the
// estimate.
#pragma once

#include "livo/map/hybrid_map_config.hpp"
#include "livo/map/map_maintenance.hpp"

#include <cstddef>

namespace livo {

class DualVisualMap;
class LocalLidarMap;

/// Exact sizes and bytes (HybridMap::stats() walks every structure).
struct HybridMapStats {
  MapMode mode = MapMode::Hybrid;
  std::size_t local_voxels = 0;           ///< LiDAR root voxels
  std::size_t visual_points_local = 0;
  std::size_t visual_points_longterm = 0;
  std::size_t bytes_lidar = 0;            ///< VoxelMap::bytes()
  std::size_t bytes_visual_local = 0;     ///< VisualMap::bytes() + scratchBytes()
  std::size_t bytes_visual_longterm = 0;  ///< VisualMap::bytes() + scratchBytes()
  std::size_t bytes_index = 0;            ///< tile index, slide and eviction work lists
  std::size_t bytes = 0;                  ///< sum of the above
  std::size_t cap_bytes = 0;              ///< 0 = no cap
  HybridMapCounters counters;
};

class ByteAccounting {
 public:
  ByteAccounting();

  /// Exact sizes and bytes of the content (mode, cap_bytes and counters are left at their defaults:
  /// HybridMap fills them). `work_bytes`: the slide policy's and the memory cap's work lists.
  static HybridMapStats count(const LocalLidarMap& lidar, const DualVisualMap& visual, std::size_t work_bytes);
  /// O(1) estimate of the bytes count() would give.
  std::size_t estimate(const LocalLidarMap& lidar, const DualVisualMap& visual) const;
  /// Exact count that recalibrates the estimate: the bytes per item (scratch buffers apart, as fixed
  /// bytes; the index goes with the root voxels) and the growth per inserted LiDAR point (what the
  /// estimate missed, smoothed). Returns the exact bytes.
  std::size_t recount(const LocalLidarMap& lidar, const DualVisualMap& visual, std::size_t work_bytes);
  /// Bytes per LiDAR root voxel (index included) of the last exact count (or the default).
  double bytesPerRoot() const { return bytes_per_root_; }

 private:
  double bytes_per_root_;
  double bytes_per_local_point_;
  double bytes_per_longterm_point_;
  std::size_t fixed_bytes_ = 0;  ///< scratch buffers and parts without items: not proportional to the counts
  double growth_per_point_ = 0.0;  ///< bytes per inserted LiDAR point beyond new roots (learnt)
  bool counted_ = false;           ///< recount() ran (later rates are smoothed)
  // Growth since the last exact count: the parts' running totals at that count.
  std::size_t points_at_count_ = 0;        ///< LocalLidarMap::insertedPoints()
  std::size_t observations_at_count_ = 0;  ///< DualVisualMap::addedObservations()
};

}  // namespace livo
