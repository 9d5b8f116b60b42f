// The plain structs of the estimator <-> map server protocol (LIVO_MAP_QUERY, LIVO_SUBMAP,
// LIVO_MAP_UPDATE, LIVO_MAP_STATS; the messages and their conversions are in livo/io/map_messages.hpp).
// Per frame the estimator sends a MapQuery for the root voxels its predicted scan touches; the map
// server answers with a Submap of the plane leaves of those voxels. A frame that runs a visual update
// sends a second query naming the visual voxels of its registered scan; that Submap carries every
// visual point of those voxels. After the frame a MapUpdate carries the registered points and the
// changed visual points.
#pragma once

#include "livo/common/types.hpp"
#include "livo/map/plane.hpp"
#include "livo/map/point_cov.hpp"
#include "livo/map/visual_point.hpp"
#include "livo/map/voxel_key.hpp"

#include <array>
#include <cstdint>
#include <utility>
#include <vector>

namespace livo {

/// Estimator -> map server: what the next frame needs (map_query_t).
struct MapQuery {
  Utime utime = 0;
  std::int64_t request_id = 0;             ///< echoed by the submap; strictly increasing
  Pose T_world_imu = Pose::Identity();     ///< predicted IMU pose
  double radius_m = 0.0;                   ///< planes wanted within this distance of the IMU, m
  std::vector<VoxelKey> keys;              ///< root voxels touched by the predicted scan (must fit int32)
  std::vector<VoxelKey> visual_keys;       ///< visual voxels touched by the registered scan (must fit int32)
  bool want_visual = false;                ///< answer with the visual points of visual_keys
  Pose T_world_camera = Pose::Identity();  ///< predicted camera pose (always sent, always validated)
  double max_visual_depth_m = 0.0;         ///< m
};

/// One plane leaf of a submap (plane_t). `plane.d` is recomputed as -n^T q on the way in; `plane.layer`
/// mirrors `layer`; eig_max = radius^2, eig_mid = 0 (not transmitted) and is_plane = true.
struct SubmapPlane {
  VoxelKey key;                                 ///< root voxel (must fit int32)
  int layer = 0;                                ///< octree layer of the leaf, 0..3 (0 = root)
  std::array<std::int8_t, 3> octant{{-1, -1, -1}};  ///< child path: octant[l] in 0..7 for l < layer, else -1
  Plane plane;
  bool frozen = false;                          ///< no longer updated
};

/// Map server -> estimator: the answer to a MapQuery (submap_t).
struct Submap {
  Utime utime = 0;               ///< utime of the query
  std::int64_t request_id = 0;   ///< request_id of the query
  double voxel_size_m = 0.5;     ///< root voxel edge, m (> 0)
  std::vector<SubmapPlane> planes;
  /// Candidate visual points: every point of the local and long-term visual maps in the visual voxels
  /// the query named (the estimator selects among them as VisualMap::retrieve does).
  std::vector<VisualPoint> visual_points;
  /// Visual point ids below this are taken in the map server's maps: new points use ids from here on.
  std::int64_t next_visual_point_id = 1;
};

/// Estimator -> map server after a frame (map_update_t). Points travel as float world coordinates.
struct MapUpdate {
  Utime utime = 0;
  std::int64_t request_id = 0;  ///< of the frame's query
  Pose T_world_imu = Pose::Identity();
  std::vector<PointWithCov> points;
  /// Visual points created or changed by the frame, in full: each replaces the map server's point of
  /// the same id (or is added to the local visual map). A point without observations deletes that id.
  std::vector<VisualPoint> new_visual_points;
  /// Single new observations of points not sent in full: appended, then the point is refined.
  std::vector<std::pair<std::int64_t, VisualObservation>> observations;  ///< (visual point id, observation)
};

/// Map server health (map_stats_t); every count >= 0.
struct MapStats {
  Utime utime = 0;                          ///< latest message time seen
  std::int64_t local_voxels = 0;            ///< root voxels in the local map
  std::int64_t local_planes = 0;
  std::int64_t visual_points_local = 0;
  std::int64_t visual_points_longterm = 0;
  std::int64_t bytes = 0;                   ///< accounted bytes of all map structures
  std::int64_t bytes_cap = 0;               ///< memory cap, bytes (0 = none)
  std::int64_t evicted_visual_points = 0;   ///< since start, by the memory cap
  std::int64_t evicted_voxels = 0;          ///< since start, by the memory cap
  std::int64_t slides = 0;                  ///< local map slides since start
  std::int64_t queries_answered = 0;
  float last_slide_ms = 0.f;
};

}  // namespace livo
