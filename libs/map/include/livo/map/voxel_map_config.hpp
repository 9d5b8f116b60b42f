// Configuration of the LiDAR voxel plane map (docs/algorithms.md section 3, FAST-LIVO2 "lio" keys).
#pragma once

#include "livo/common/config.hpp"

#include <vector>

namespace livo {

struct VoxelMapConfig {
  double voxel_size_m = 0.5;  ///< edge of a root voxel, m (FAST-LIVO2 voxel_size)
  int max_layer = 2;          ///< deepest octree layer; 2 gives 3 levels (0.5 / 0.25 / 0.125 m)
  /// A node at layer l fits its first plane once it holds more than layer_init_num[l] points.
  /// Needs at least max_layer + 1 entries, each >= 2 (a plane needs 3 points).
  std::vector<int> layer_init_num = {5, 5, 5, 5, 5};
  int max_points = 50;             ///< a leaf holding this many points is frozen (max_points_num)
  int refit_new_points = 6;        ///< a leaf refits all its points after this many new ones
  double min_eigen_value = 0.0025; ///< planar when the smallest covariance eigenvalue is below, m^2
  double sigma_num = 3.0;          ///< association gates: in-plane radius and distance, in sigmas

  /// Reads the keys above (same names) from `node`, e.g. the "lio" or "map" section, and validates
  /// them; throws ConfigError naming the key on a bad value.
  void load(const ConfigNode& node);
  /// Initialisation threshold of a layer (entries beyond the list repeat its last value).
  int initNum(int layer) const;
};

}  // namespace livo
