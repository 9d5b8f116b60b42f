// Sliding of the hybrid map (docs/algorithms.md "The two ideas", 3; section 3 "Sliding"):
//   - local cube: edge local_edge_m, centred on the robot position of the last slide; a slide happens
//     once the robot is slide_distance_m from that position (Euclidean). LiDAR root voxels whose centre
//     leaves the cube are deleted; local visual points whose visual voxel centre leaves it move to the
//     long-term map (only points with a reference patch and longterm_min_observations observations,
//     keeping only that reference when longterm_reference_only; the others are dropped); long-term points whose voxel centre is inside
//     the new local cube move back (revisits).
//   - long-term cube: edge longterm_edge_m, slid every longterm_slide_m; long-term points leaving it are
//     deleted.
// Cost: a slide only visits the index tiles that reach out of the new cube (RootTileIndex) and the
// visual points; the erasures and point moves are work lists spread over updates within the
// per-update budget (WorkBudget), every item judged again when it is done.
#pragma once

#include "livo/common/so3.hpp"
#include "livo/map/hybrid_map_config.hpp"
#include "livo/map/map_maintenance.hpp"
#include "livo/map/visual_point.hpp"
#include "livo/map/voxel_key.hpp"

#include <cstddef>
#include <cstdint>
#include <vector>

namespace livo {

class SlidePolicy {
 public:
  explicit SlidePolicy(const HybridMapConfig& config);

  /// Starts the slides that are due at `robot`: long-term first (so that points leaving the local cube
  /// are judged against the new long-term cube), then local. The first call centres both cubes.
  void startDue(const Vec3& robot, MapWork& work);
  /// Does pending slide work (moves to and from the long-term map, long-term deletions, then root
  /// voxel removals tile by tile) while the budget lasts.
  void doPending(WorkBudget& budget, MapWork& work);

  /// Cube centres (meaningful after the first update in hybrid mode).
  const Vec3& localCenter() const { return local_center_; }
  const Vec3& longtermCenter() const { return longterm_center_; }
  /// Items left in the work lists.
  std::size_t pending() const;
  /// Capacity of the work lists, bytes.
  std::size_t workBytes() const;
  /// Empties the work lists (keeping their capacity); the next startDue() centres both cubes again.
  void clear();

 private:
  void startLocal(const Vec3& center, MapWork& work);
  void startLongterm(const Vec3& center, MapWork& work);
  /// Moves one local visual point to the long-term map (or drops it); returns false when unknown.
  bool moveToLongterm(std::int64_t id, MapWork& work);
  /// The long-term voxel of `p` already holds longterm_points_per_voxel points (never with 0).
  bool longtermVoxelFull(const VisualPoint& p, MapWork& work) const;
  bool outsideLocal(const Vec3& c) const;
  bool outsideLongterm(const Vec3& c) const;

  double local_edge_m_, slide_distance_m_, longterm_edge_m_, longterm_slide_m_;
  bool longterm_reference_only_;
  bool longterm_enabled_;
  int longterm_per_voxel_;
  int longterm_min_obs_;  ///< HybridMapConfig::longterm_min_observations

  bool started_ = false;
  Vec3 local_center_ = Vec3::Zero();
  Vec3 longterm_center_ = Vec3::Zero();

  // Work lists (cursor = next entry to process).
  std::vector<VoxelKey> pending_tiles_;
  std::size_t tile_cursor_ = 0;
  std::vector<std::int64_t> pending_moves_;  ///< local visual ids outside the local cube
  std::size_t move_cursor_ = 0;
  std::vector<std::int64_t> pending_returns_;  ///< long-term ids inside the local cube
  std::size_t return_cursor_ = 0;
  std::vector<std::int64_t> pending_deletes_;  ///< long-term ids outside the long-term cube
  std::size_t delete_cursor_ = 0;
};

}  // namespace livo
