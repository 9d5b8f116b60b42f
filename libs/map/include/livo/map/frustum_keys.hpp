// The visual voxels a camera sees, without a LiDAR scan: for a frame whose LiDAR update failed (no
// returns, too few matches), the visual points are retrieved from the voxels along the rays through
// the centres of the selection grid's cells, from min_depth_m to max_depth_m in steps of half a voxel.
#pragma once

#include "livo/common/types.hpp"
#include "livo/map/voxel_key.hpp"

#include <vector>

namespace livo {

class CameraModel;

/// Distinct visual voxel keys (voxel edge `voxel_size_m`) along the rays through the centres of the
/// cells of a grid with `cell_px` pixels per cell, sorted. Empty for a non-positive depth range.
std::vector<VoxelKey> frustumVoxelKeys(const CameraModel& cam, const Pose& T_world_camera, double voxel_size_m,
                                       int cell_px, double min_depth_m, double max_depth_m);

}  // namespace livo
