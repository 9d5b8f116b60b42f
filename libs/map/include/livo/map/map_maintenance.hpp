// What the hybrid map's per-frame maintenance (HybridMap::update: the slides of slide_policy.hpp and
// the memory cap of memory_cap.hpp) reports, counts and spends: the report of one update, the
// cumulative counters, the per-update work budget and the parts one maintenance step works on.
#pragma once

#include <cstddef>
#include <limits>

namespace livo {

class ByteAccounting;
class DualVisualMap;
class LocalLidarMap;

/// What one update() did.
struct MapUpdateReport {
  bool slid = false;             ///< the local cube was re-centred in this update
  bool longterm_slid = false;    ///< the long-term cube was re-centred in this update
  std::size_t removed_voxels = 0;          ///< LiDAR root voxels deleted by slides
  std::size_t moved_to_longterm = 0;       ///< visual points moved local -> long-term
  std::size_t moved_to_local = 0;          ///< long-term points back inside the local cube
  std::size_t deleted_points = 0;          ///< visual points deleted by slides (beyond the long-term cube, no reference)
  std::size_t evicted_longterm_points = 0; ///< memory cap
  std::size_t evicted_local_voxels = 0;    ///< memory cap
  std::size_t evicted_local_points = 0;    ///< memory cap
  std::size_t pending = 0;       ///< work left for the next updates (tiles, points, eviction victims)
  bool recounted = false;        ///< an exact byte count was made (after the slide work)
  /// Accounted bytes after the update: the O(1) estimate (bytesEstimate()), equal to the exact count
  /// when one was made and nothing was evicted after it.
  std::size_t bytes = 0;
  double ms = 0.0;               ///< wall time of the update
};

/// Cumulative counters since construction.
struct HybridMapCounters {
  std::size_t updates = 0, slides = 0, longterm_slides = 0;
  std::size_t removed_voxels = 0, moved_to_longterm = 0, moved_to_local = 0, deleted_points = 0;
  std::size_t eviction_events = 0, evicted_longterm_points = 0, evicted_local_voxels = 0, evicted_local_points = 0;
  std::size_t recounts = 0;
  double max_update_ms = 0.0;  ///< worst update() (slide work, evictions, recounts)
  double max_slide_ms = 0.0;   ///< worst update() that started a slide
};

/// Items (root voxels removed, visual points moved, deleted or evicted) one update may still handle:
/// HybridMapConfig::max_removals_per_update, or unlimited.
struct WorkBudget {
  std::size_t left;
  bool unlimited;

  static WorkBudget perUpdate(int max_removals) { return {std::size_t(max_removals), max_removals == 0}; }
  static WorkBudget none() { return {0, true}; }  ///< no limit
  /// Takes one item; false when the budget is spent.
  bool take() {
    if (unlimited) return true;
    if (left == 0) return false;
    --left;
    return true;
  }
  bool exhausted() const { return !unlimited && left == 0; }
  std::size_t remaining() const { return unlimited ? std::numeric_limits<std::size_t>::max() : left; }
  /// Takes `n` items at once (n <= remaining()).
  void spend(std::size_t n) {
    if (!unlimited) left -= n;
  }
};

/// One maintenance step's view of the map: the content it changes, the byte estimate it checks, and
/// where its work is tallied (the update's report and the cumulative counters).
struct MapWork {
  LocalLidarMap& lidar;
  DualVisualMap& visual;
  const ByteAccounting& bytes;
  MapUpdateReport& rep;
  HybridMapCounters& total;
};

}  // namespace livo
