// The hybrid map's memory cap (memory_cap_mb > 0; docs/algorithms.md section 8, "Memory"): when the
// accounted bytes exceed cap_high_water of the cap, the farthest long-term visual points (from the
// robot, Euclidean) are evicted first, then the farthest local content (LiDAR root voxels by centre and
// local visual points by position, in one order), content worth the bytes down to cap_low_water of the
// cap. The victims are a work list done within the per-update budget; over the cap itself, evictions
// go beyond the budget until under it.
// The cap is checked on the O(1) byte estimate (byte_accounting.hpp); this part also decides when an
// exact count is due: at the first check, after each completed eviction and every recount_interval
// checks.
#pragma once

#include "livo/common/so3.hpp"
#include "livo/map/hybrid_map_config.hpp"
#include "livo/map/map_maintenance.hpp"
#include "livo/map/voxel_key.hpp"

#include <cstddef>
#include <cstdint>
#include <vector>

namespace livo {

class MemoryCap {
 public:
  explicit MemoryCap(const HybridMapConfig& config);

  /// Changes the cap (bytes, 0 = none): an exact count is due at the next check; without a cap the
  /// eviction plan is dropped.
  void setCapBytes(std::size_t cap_bytes);
  std::size_t capBytes() const { return cap_bytes_; }
  /// Counts one cap check (per update, with a cap): true when an exact count is due now (the caller
  /// makes it, ByteAccounting::recount, before enforce()).
  bool exactCountDue();
  /// The content changed behind the estimate's back (e.g. a map file was loaded): an exact count is
  /// due at the next check.
  void requestExactCount() { calibrated_ = false; }

  /// Evicts planned victims within the budget; with stop_below > 0, stops once the estimate is at or
  /// below it.
  void evict(WorkBudget& budget, MapWork& work, double stop_below);
  /// Over the high-water mark, plans an eviction (unless one is under way) and starts it with what is
  /// left of the budget; over the cap itself, evicts beyond the budget down to the low-water mark.
  void enforce(const Vec3& robot, WorkBudget& budget, MapWork& work);

  /// Victims left to evict.
  std::size_t pending() const { return pending_evictions_.size() - evict_cursor_; }
  /// Capacity of the victim list, bytes.
  std::size_t workBytes() const { return pending_evictions_.capacity() * sizeof(Victim); }
  /// Empties the victim list (keeping its capacity).
  void clear();

 private:
  struct Victim {
    enum Kind : std::uint8_t { LongtermPoint, LocalPoint, Root } kind;
    VoxelKey key;     ///< Root
    std::int64_t id;  ///< points
  };
  /// Lists the victims (farthest long-term points, then farthest local content) worth `need` bytes.
  void plan(const Vec3& robot, const MapWork& work, double need);
  /// Local content (root voxels and local points) farthest first, appended until `need` bytes.
  void planLocal(const Vec3& robot, const MapWork& work, double need);

  std::size_t cap_bytes_;
  double high_water_, low_water_;
  int recount_interval_;

  std::vector<Victim> pending_evictions_;  ///< farthest first
  std::size_t evict_cursor_ = 0;
  int checks_since_count_ = 0;
  bool calibrated_ = false;  ///< an exact count was made since the cap was set
};

}  // namespace livo
