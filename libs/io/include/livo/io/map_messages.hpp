// Conversions between the map's plain structs and the map messages (map_query_t, submap_t, plane_t,
// visual_point_t, patch_t, map_update_t, map_stats_t), with validation in the pattern of convert.hpp:
// toMsg() sets every count from the vectors; fromMsg() validates first and leaves `out` untouched on
// failure; validate() names the field, e.g. "submap_t.planes: num_planes declares 5 but the array has
// 4 values" or "submap_t.visual_points[2].patches[0].levels: expected 3 (PatchPyramid::kLevels), got 2".
//
// Precision: world points of map_update_t and the float fields (plane radius and min eigenvalue,
// position_cov, patch pixel / inv_exposure / score) travel as float; everything else is exact except
// rotations, which travel as quaternions (round trip to ~1e-15).
#pragma once

#include "livo/io/convert.hpp"
#include "livo/map/plane.hpp"
#include "livo/map/point_cov.hpp"
#include "livo/map/visual_point.hpp"
#include "livo/map/voxel_key.hpp"

#include <livo/map_query_t.hpp>
#include <livo/map_stats_t.hpp>
#include <livo/map_update_t.hpp>
#include <livo/patch_t.hpp>
#include <livo/plane_t.hpp>
#include <livo/submap_t.hpp>
#include <livo/visual_point_t.hpp>

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
  bool want_visual = false;                ///< the frame will run a visual update
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
  std::vector<VisualPoint> visual_points;
};

/// Estimator -> map server after a frame (map_update_t). Points travel as float world coordinates.
struct MapUpdate {
  Utime utime = 0;
  std::int64_t request_id = 0;  ///< of the frame's query
  Pose T_world_imu = Pose::Identity();
  std::vector<PointWithCov> points;
  std::vector<VisualPoint> new_visual_points;
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

// ---- struct -> message. Counts come from the vectors. Keys that do not fit int32 throw
// std::out_of_range naming the key; everything else is copied as is (validate() to check). ----
/// patch_t: levels = PatchPyramid::kLevels (3), size = PatchPyramid::kCrop (12: the stored crop side,
/// patch proper kSize = 8 plus kMargin on each side), num_values = 432.
livo::patch_t toMsg(const VisualObservation& o);
/// visual_point_t: position_cov as (xx, xy, xz, yy, yz, zz) of the symmetric part; bad_updates and
/// last_seen are local map bookkeeping and are not sent (they come back as 0).
livo::visual_point_t toMsg(const VisualPoint& p);
livo::plane_t toMsg(const SubmapPlane& p);
livo::map_query_t toMsg(const MapQuery& q);
livo::submap_t toMsg(const Submap& s);
livo::map_update_t toMsg(const MapUpdate& u);
livo::map_stats_t toMsg(const MapStats& s);

// ---- message -> struct: validate(), then convert; `out` is untouched on failure. ----
Validation fromMsg(const livo::patch_t& m, VisualObservation& out, const MessageLimits& lim = {});
Validation fromMsg(const livo::visual_point_t& m, VisualPoint& out, const MessageLimits& lim = {});
Validation fromMsg(const livo::plane_t& m, SubmapPlane& out, const MessageLimits& lim = {});
Validation fromMsg(const livo::map_query_t& m, MapQuery& out, const MessageLimits& lim = {});
Validation fromMsg(const livo::submap_t& m, Submap& out, const MessageLimits& lim = {});
Validation fromMsg(const livo::map_update_t& m, MapUpdate& out, const MessageLimits& lim = {});
Validation fromMsg(const livo::map_stats_t& m, MapStats& out, const MessageLimits& lim = {});

// ---- validation: declared counts equal array sizes and respect MessageLimits (num_keys and
// num_points against max_points, planes against max_planes, visual points and observations against
// max_visual_points, patches against max_patches_per_point, patch values against max_patch_values);
// values finite; normals unit within 1e-3; quaternions non-zero; covariances finite, symmetric with a
// non-negative diagonal and PSD 2x2 minors; patches of exactly 3 levels of 12 x 12; times >= 0. ----
Validation validate(const livo::patch_t& m, const MessageLimits& lim = {});
Validation validate(const livo::visual_point_t& m, const MessageLimits& lim = {});
Validation validate(const livo::plane_t& m, const MessageLimits& lim = {});
Validation validate(const livo::map_query_t& m, const MessageLimits& lim = {});
Validation validate(const livo::submap_t& m, const MessageLimits& lim = {});
Validation validate(const livo::map_update_t& m, const MessageLimits& lim = {});
Validation validate(const livo::map_stats_t& m, const MessageLimits& lim = {});

}  // namespace livo
