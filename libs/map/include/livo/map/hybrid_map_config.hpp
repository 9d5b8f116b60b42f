// Configuration of the hybrid map (docs/algorithms.md "The two ideas", 3; section 3 "Sliding"; section 8
// "Memory"): a local map (LiDAR planes + visual points) bounded by a cube around the robot, a sparse
// long-term visual map bounded by a larger cube, and an optional memory cap. Read from the rig
// config's `map` section; the mode is a command-line choice (livo-run --map-mode) set in code.
#pragma once

#include "livo/common/config.hpp"
#include "livo/common/modes.hpp"

#include <cstddef>
#include <string>

namespace livo {

// MapMode (livo/common/modes.hpp): hybrid: local cube + long-term visual map + memory cap (this
// project); global: one unbounded map, never slid nor evicted (FAST-LIVO2 behaviour).

struct HybridMapConfig {
  MapMode mode = MapMode::Hybrid;  ///< command line (--map-mode), not read from the file

  // Local map: LiDAR root voxels and visual points (paper: edge 200 m, slid every 20 m).
  double local_edge_m = 200.0;     ///< edge of the local cube centred on the robot at the last slide, m
  double slide_distance_m = 20.0;  ///< slide once the robot is this far from the last slide position, m

  // Long-term visual map: visual points that left the local cube (paper: edge 800 m, slid every 100 m).
  /// false: no long-term map; visual points leaving the local cube are deleted, not moved (the
  /// ablation `scripts/bench --ablation longterm`: what the long-term map is worth).
  bool longterm_enabled = true;
  double longterm_edge_m = 800.0;   ///< edge of the long-term cube, m (>= local_edge_m)
  double longterm_slide_m = 100.0;  ///< long-term slide distance, m
  /// A point moving to the long-term map keeps only its reference observation (one patch pyramid,
  /// about 0.9 kB per point instead of up to max_observations times that); false keeps them all.
  bool longterm_reference_only = true;
  /// At most this many points per visual voxel in the long-term map: a point leaving the local cube
  /// into a long-term voxel that is full is deleted (0: no limit). On a revisit the retrieval uses one
  /// point per image grid cell, so a sparse long-term map gives nearly the same references.
  int longterm_points_per_voxel = 0;
  /// Only points with at least this many observations (VisualPoint::views, ever stored) when they
  /// leave the local cube (matched from
  /// that many views: their patch has shown it can be found again) move to the long-term map; the
  /// others are deleted. On the revisit scenario (2026-12-02) 80 % of the points leaving the cube had
  /// one observation and were used again after a revisit at 48 %, against 63-95 % for those with two
  /// or more; 2 keeps a fifth of the points and the same error. 1: every point with a patch.
  int longterm_min_observations = 2;

  // Memory budget (hybrid mode only).
  double memory_cap_mb = 0.0;  ///< cap on the accounted bytes of all map structures, MiB; 0 = none
  /// Evictions start when the bytes exceed this fraction of the cap ... (the margin up to the cap
  /// absorbs the growth while an eviction is spread over updates)
  double cap_high_water = 0.95;
  double cap_low_water = 0.85;  ///< ... and remove content worth the bytes down to this fraction
  /// With a cap, the exact byte count (a walk of every structure: the slowest map step, ~4-7 ms per
  /// 30 MB of LiDAR map) is made at the first update, after each completed eviction and every this
  /// many updates; in between the cap is checked on an O(1) estimate (counts times the bytes per
  /// item of the last count, which falls behind as existing root voxels collect points).
  int recount_interval = 20;

  // Incremental sliding (a slide must not stall a frame).
  double tile_edge_m = 10.0;  ///< edge of the index tiles grouping LiDAR root voxels, m
  /// Root voxels removed plus visual points moved, deleted or evicted per update(); the rest of a
  /// slide's or an eviction's work carries over to the next updates. 0 = unlimited (all at once).
  int max_removals_per_update = 1000;

  /// Reads the keys above (same names) from `node` (the `map` section) and validates them; throws
  /// ConfigError naming the key on a bad value.
  void load(const ConfigNode& node);
  /// Throws std::invalid_argument naming the first invalid field (used by HybridMap's constructor).
  void validate() const;
  std::size_t capBytes() const { return static_cast<std::size_t>(memory_cap_mb * 1024.0 * 1024.0); }
};

}  // namespace livo
