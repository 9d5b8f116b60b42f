// Voxel-grid downsampling: one output point per occupied voxel of a regular grid.
//
// Voxel of p: key = floor(p / leaf) per axis (correct for negative coordinates), i.e. the cube
// [k leaf, (k+1) leaf). Output per voxel: the centroid of its points. For LidarPoint the time offset
// and intensity are the means too: under motion distortion the position of a point moves roughly
// linearly with its time, so the mean time is the time that belongs to the centroid (the same choice
// as PCL's VoxelGrid, which FAST-LIVO2 uses). The ring is the one of the first point of the voxel.
// Output order: voxels in order of their first point in the input (deterministic). Non-finite points
// and points beyond 2^30 leaves from the origin are skipped. leaf_m <= 0 (or non-finite) returns the
// input unchanged.
//
// Implementation: one pass with an open-addressing hash table (linear probing, power-of-two size,
// at least twice the point count), accumulating sums in double; no per-voxel allocation.
#pragma once

#include "livo/common/types.hpp"

#include <Eigen/Core>

#include <vector>

namespace livo {

std::vector<LidarPoint> voxelDownsample(const std::vector<LidarPoint>& points, float leaf_m);

/// The same grid on plain positions (e.g. world-frame points): centroids per voxel.
std::vector<Eigen::Vector3d> voxelDownsample(const std::vector<Eigen::Vector3d>& points, double leaf_m);

}  // namespace livo
