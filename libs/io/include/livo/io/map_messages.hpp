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
#include "livo/map/map_protocol.hpp"
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

// ---- struct -> message. Counts come from the vectors. Keys that do not fit int32 throw
// std::out_of_range naming the key; everything else is copied as is (validate() to check). ----
/// patch_t: levels = PatchPyramid::kLevels (3), size = PatchPyramid::kCrop (12: the stored crop side,
/// patch proper kSize = 8 plus kMargin on each side), num_values = 432.
livo::patch_t toMsg(const VisualObservation& o);
/// visual_point_t: position_cov as (xx, xy, xz, yy, yz, zz) of the symmetric part; bad_updates travels
/// (the outlier rule spans frames); last_seen is local map bookkeeping, not sent (comes back as 0).
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
