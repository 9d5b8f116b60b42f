// Hybrid map (ALGORITHMS.md "The two ideas", 3; sections 3 "Sliding" and 8 "Memory").
//
// hybrid mode:
//   - local map: the LiDAR voxel plane map and the local visual map, limited to a cube of edge
//     local_edge_m centred on the robot position of the last slide; a slide happens once the robot is
//     slide_distance_m from that position (Euclidean). LiDAR root voxels whose centre leaves the cube
//     are deleted; visual points whose visual voxel centre leaves it move to the long-term map;
//     long-term points whose voxel centre is inside the new local cube move back (revisits).
//   - long-term visual map: visual points that have a reference patch (others are dropped when they
//     leave the local cube), keeping only that reference (longterm_reference_only), limited to a cube
//     of edge longterm_edge_m slid every longterm_slide_m; points leaving it are deleted.
//   - memory cap (memory_cap_mb > 0): when the accounted bytes exceed cap_high_water of the cap, the
//     farthest long-term visual points (from the robot, Euclidean) are evicted first, then the
//     farthest local content (LiDAR root voxels by centre and local visual points by position, in one
//     order), content worth the bytes down to cap_low_water of the cap.
//   Both visual maps are searched for the points in view (same scan-voxel retrieval in each; per grid
//   cell the nearest of the two winners).
// global mode (FAST-LIVO2 behaviour): one unbounded LiDAR map and one visual map; update() does nothing.
//
// Cost: a slide only visits the index tiles that reach out of the new cube (RootTileIndex) and the
// visual points; the erasures, point moves and evictions are spread over updates, at most
// max_removals_per_update per call (evictions first). The cap check between exact byte counts is
// O(1) (counts times the bytes per item of the last exact count); the exact count walks every
// structure (at the first check, then every recount_interval updates).
//
// Pointers: VisualPoint* from pointsInView / find and Plane* from lidarMap().findBestPlane stay valid
// until the next update(), insertLidar() (planes only), removeBadPoints() (the removed points only) or
// clear(). Callers must not change a visual point's p_world or id.
// Thread safety: const member functions may run concurrently; everything else needs exclusive access.
#pragma once

#include "livo/map/hybrid_map_config.hpp"
#include "livo/map/hybrid_map_tiles.hpp"
#include "livo/map/visual_map.hpp"
#include "livo/map/voxel_map.hpp"

#include <cstddef>
#include <cstdint>
#include <vector>

namespace livo {

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

/// Exact sizes and bytes (stats() walks every structure).
struct HybridMapStats {
  MapMode mode = MapMode::Hybrid;
  std::size_t local_voxels = 0;           ///< LiDAR root voxels
  std::size_t visual_points_local = 0;
  std::size_t visual_points_longterm = 0;
  std::size_t bytes_lidar = 0;            ///< VoxelMap::bytes()
  std::size_t bytes_visual_local = 0;     ///< VisualMap::bytes() + scratchBytes()
  std::size_t bytes_visual_longterm = 0;  ///< VisualMap::bytes() + scratchBytes()
  std::size_t bytes_index = 0;            ///< tile index and slide work lists
  std::size_t bytes = 0;                  ///< sum of the above
  std::size_t cap_bytes = 0;              ///< 0 = no cap
  HybridMapCounters counters;
};

class HybridMap {
 public:
  HybridMap(HybridMapConfig config, VoxelMapConfig lidar_config, VisualMapConfig visual_config);

  // --- LiDAR part -------------------------------------------------------------------------------
  /// Inserts world points into the local LiDAR map (VoxelMap::insert) and records their root voxels in
  /// the tile index (hybrid mode). Returns the number of points taken.
  std::size_t insertLidar(const std::vector<PointWithCov>& points);
  const VoxelMap& lidarMap() const { return lidar_; }

  // --- Visual part (the per-frame operations of VisualMap, over both visual maps) -----------------
  ImageGrid gridFor(const CameraModel& cam) const { return local_visual_.gridFor(cam); }
  /// VisualMap::pointsInView on the local and on the long-term map; per grid cell the winner with the
  /// smaller depth (ties: smaller id) is kept, ordered by cell. A cell whose local winner is occluded
  /// may still receive the long-term winner (each map applies the occlusion test to its own winner).
  std::vector<VisualPoint*> pointsInView(const CameraModel& cam, const Pose& T_world_camera,
                                         const std::vector<Vec3>& scan_points_world,
                                         std::vector<Vec2>* pixels = nullptr);
  /// Cells holding a point returned by the last pointsInView (for addPoints).
  const std::vector<bool>& occupiedCells() const { return occupied_; }
  /// Summed counters of the last pointsInView (selected = points returned).
  const VisualRetrievalStats& lastRetrieval() const { return retrieval_; }
  /// Of those, how many came from the long-term map.
  std::size_t lastRetrievalLongterm() const { return retrieved_longterm_; }
  /// New visual points go to the local map (VisualMap::addPoints).
  int addPoints(const Image& gray, const CameraModel& cam, const Pose& T_world_camera, float inv_exposure, Utime t,
                const std::vector<NewPointCandidate>& candidates, const std::vector<bool>& occupied_cells);
  /// VisualMap::addObservation / refine (with the local LiDAR map) / reportPhotometricError on the
  /// map that holds `p` (either; `p` must come from this map).
  bool addObservation(VisualPoint& p, const Image& gray, const Pose& T_world_camera, const Vec2& px,
                      float inv_exposure, Utime t);
  void refine(VisualPoint& p);
  void reportPhotometricError(VisualPoint& p, double mean_sq_error, double gate);
  /// VisualMap::removeBadPoints on both maps; returns the count.
  std::size_t removeBadPoints();
  /// True when `p` is held by the long-term map.
  bool isLongterm(const VisualPoint& p) const { return longterm_visual_.find(p.id) == &p; }

  // --- Remote access (the map server's side of livo/map/map_protocol.hpp) ------------------------
  /// Copies of every point of both visual maps in the given visual voxels (duplicate keys ignored),
  /// appended to `out`; returns the count appended.
  std::size_t copyVisualPointsIn(const std::vector<VoxelKey>& visual_keys, std::vector<VisualPoint>& out) const;
  /// Replaces the point with p.id (in whichever map holds it) by `p`, or adds `p` to the local map
  /// when the id is unknown; a `p` without observations removes the point instead. Returns false when
  /// `p` was rejected (non-finite position, or a reference index outside its observations).
  bool upsertVisualPoint(VisualPoint p);
  /// Appends an observation to a point and refines it (VisualMap::refine with the local LiDAR map);
  /// false when the id is unknown or the point is converged (frozen).
  bool appendObservation(std::int64_t id, const VisualObservation& obs);
  /// Ids below this are taken in either visual map.
  std::int64_t nextVisualPointId() const { return std::max(local_visual_.nextId(), longterm_visual_.nextId()); }

  const VisualMap& localVisual() const { return local_visual_; }
  const VisualMap& longtermVisual() const { return longterm_visual_; }
  /// Direct access for tools and tests (e.g. inserting prepared points); the rules above still hold.
  VisualMap& localVisual() { return local_visual_; }

  // --- Maintenance --------------------------------------------------------------------------------
  /// Once per frame, after the map insertions: starts a slide when due (local, long-term), does up
  /// to max_removals_per_update items of pending work (evictions, then slide work), then checks the
  /// memory cap: over its high-water mark it plans an eviction and starts it with what is left of
  /// the budget; over the cap itself it evicts beyond the budget until under it, so that the
  /// accounted bytes (estimate) are under the cap after every call whenever the cap can hold anything. The first call centres both cubes (counted as a slide). Hybrid mode
  /// only; global mode returns at once. Non-finite positions are ignored. Invalidates handed-out
  /// pointers (see the file comment).
  MapUpdateReport update(const Vec3& robot_position);
  /// Finishes all pending slide work now (e.g. before an exact comparison in a test).
  void finishPendingWork();

  /// Exact counts and bytes: walks every structure (stats rate, not per frame).
  HybridMapStats stats() const;
  std::size_t bytes() const { return stats().bytes; }
  /// O(1) estimate: counts times the bytes per item of the last exact count (or defaults), plus the
  /// growth since that count (inserted LiDAR points times a learnt rate, added observations).
  std::size_t bytesEstimate() const;
  const HybridMapCounters& counters() const { return counters_; }
  /// Changes the memory cap (MiB, 0 = none; e.g. a map server's --memory-cap-mb); applied by the next
  /// update(). Throws std::invalid_argument on a negative or non-finite value.
  void setMemoryCapMb(double mb);
  const HybridMapConfig& config() const { return cfg_; }
  MapMode mode() const { return cfg_.mode; }
  /// Cube centres (meaningful after the first update in hybrid mode).
  const Vec3& localCenter() const { return local_center_; }
  const Vec3& longtermCenter() const { return longterm_center_; }
  std::size_t pendingWork() const;
  void clear();
  /// Binary form of the map's content: LiDAR octrees and both visual maps (map_file.hpp). Counters,
  /// cube centres and pending slide work are not saved: the first update() after load() centres the
  /// cubes at the robot again.
  void save(std::ostream& os) const;
  void load(std::istream& is);

 private:
  struct Budget {
    std::size_t left;
    bool unlimited;
    bool take() {
      if (unlimited) return true;
      if (left == 0) return false;
      --left;
      return true;
    }
    bool exhausted() const { return !unlimited && left == 0; }
  };
  void startLocalSlide(const Vec3& center, MapUpdateReport& rep);
  void startLongtermSlide(const Vec3& center);
  void doPendingWork(Budget& budget, MapUpdateReport& rep);
  /// Moves one local visual point to the long-term map (or drops it); returns false when unknown.
  bool moveToLongterm(std::int64_t id, MapUpdateReport& rep);
  /// Exact recount; refreshes the bytes-per-item ratios.
  std::size_t recount();
  void enforceCap(const Vec3& robot, Budget& budget, MapUpdateReport& rep);
  /// Lists the victims (farthest long-term points, then farthest local content) worth `need` bytes.
  void planEvictions(const Vec3& robot, double need);
  /// Evicts planned victims within the budget; with stop_below > 0, stops once the estimate is at or
  /// below it.
  void doEvictions(Budget& budget, MapUpdateReport& rep, double stop_below);
  bool outsideLocal(const Vec3& c) const;
  bool outsideLongterm(const Vec3& c) const;

  HybridMapConfig cfg_;
  VoxelMap lidar_;
  VisualMap local_visual_;
  VisualMap longterm_visual_;
  RootTileIndex tiles_;
  std::vector<PointWithCov> index_scratch_;  ///< one-point batch for insertLidar

  bool started_ = false;
  Vec3 local_center_ = Vec3::Zero();
  Vec3 longterm_center_ = Vec3::Zero();

  // Slide work lists (cursor = next entry to process).
  std::vector<VoxelKey> pending_tiles_;
  std::size_t tile_cursor_ = 0;
  std::vector<std::int64_t> pending_moves_;  ///< local visual ids outside the local cube
  std::size_t move_cursor_ = 0;
  std::vector<std::int64_t> pending_returns_;  ///< long-term ids inside the local cube
  std::size_t return_cursor_ = 0;
  std::vector<std::int64_t> pending_deletes_;  ///< long-term ids outside the long-term cube
  std::size_t delete_cursor_ = 0;
  struct Victim {
    enum Kind : std::uint8_t { LongtermPoint, LocalPoint, Root } kind;
    VoxelKey key;     ///< Root
    std::int64_t id;  ///< points
  };
  std::vector<Victim> pending_evictions_;  ///< memory cap, farthest first
  std::size_t evict_cursor_ = 0;

  // Byte accounting between exact counts.
  double bytes_per_root_;
  double bytes_per_local_point_;
  double bytes_per_longterm_point_;
  std::size_t fixed_bytes_ = 0;  ///< scratch buffers and parts without items: not proportional to the counts
  double growth_per_point_ = 0.0;        ///< bytes per inserted LiDAR point beyond new roots (learnt)
  std::size_t points_since_recount_ = 0;  ///< LiDAR points inserted since the last exact count
  std::size_t obs_since_recount_ = 0;     ///< visual observations added since the last exact count
  int updates_since_recount_ = 0;
  bool calibrated_ = false;      ///< an exact count was made since the cap was set

  // Merged retrieval state.
  std::vector<bool> occupied_;
  VisualRetrievalStats retrieval_;
  std::size_t retrieved_longterm_ = 0;

  HybridMapCounters counters_;
};

}  // namespace livo
