// The map server's side of the estimator protocol (livo/map/map_protocol.hpp) on a HybridMap:
// answers queries with submaps, applies map updates (insertion, visual point changes, then the
// per-frame maintenance: slides and the memory cap) and reports MapStats. livo-mapserver is a thin
// LCM adapter over this class; the tests drive it directly.
#pragma once

#include "livo/common/ms_histogram.hpp"
#include "livo/map/hybrid_map.hpp"
#include "livo/map/map_protocol.hpp"

#include <cstddef>
#include <string>

namespace livo {

struct MapServiceCounters {
  std::size_t queries = 0;            ///< answered
  std::size_t visual_queries = 0;     ///< of those, with want_visual
  std::size_t updates = 0;            ///< applied
  std::size_t stale_updates = 0;      ///< updates older than the newest applied one (applied anyway)
  std::size_t points_inserted = 0;
  std::size_t visual_upserts = 0;     ///< created or replaced visual points
  std::size_t visual_removals = 0;
  std::size_t visual_rejected = 0;    ///< points with a bad reference or position
  std::size_t observations_added = 0;
  std::size_t observations_unknown = 0;  ///< for ids not in the map (or converged points)
  double last_slide_ms = 0.0;         ///< the last update that started a slide
  double max_update_ms = 0.0;         ///< worst apply(), wall clock
  double max_update_cpu_ms = 0.0;     ///< worst apply(), the thread's CPU time (without waits for a core)
  /// Worst CPU time of apply()'s parts: LiDAR insertion, visual changes, maintenance (slides, cap).
  double max_insert_cpu_ms = 0.0, max_visual_cpu_ms = 0.0, max_maintenance_cpu_ms = 0.0;
  MsHistogram update_cpu_ms{0.1, 1000.0};  ///< every apply()'s CPU time, 0.1 ms bins (quantiles)
};

class MapService {
 public:
  MapService(HybridMapConfig map, VoxelMapConfig lidar, VisualMapConfig visual);

  /// The plane leaves of the queried root voxels (duplicates ignored; missing voxels give nothing) and,
  /// with want_visual, every visual point of the queried visual voxels in either visual map that lies
  /// in front of q.T_world_camera (depth >= the visual map's min_depth_m and, when
  /// q.max_visual_depth_m > 0, <= it).
  Submap answer(const MapQuery& q);
  /// Inserts the points, applies the visual point changes and observations, then runs the map's
  /// per-frame maintenance at the update's position (HybridMap::update).
  MapUpdateReport apply(const MapUpdate& u);
  /// Exact counts (walks the map: call at stats rate).
  MapStats stats() const;

  HybridMap& map() { return map_; }
  const HybridMap& map() const { return map_; }
  const MapServiceCounters& counters() const { return counters_; }
  Utime latestTime() const { return latest_; }

 private:
  HybridMap map_;
  MapServiceCounters counters_;
  Utime latest_ = 0;
  Utime latest_update_ = -1;
};

}  // namespace livo
