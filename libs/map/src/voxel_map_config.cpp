#include "livo/map/voxel_map_config.hpp"

#include <algorithm>
#include <string>

namespace livo {

void VoxelMapConfig::load(const ConfigNode& node) {
  node.get("voxel_size_m", voxel_size_m);
  node.get("max_layer", max_layer);
  node.get("layer_init_num", layer_init_num);
  node.get("max_points", max_points);
  node.get("refit_new_points", refit_new_points);
  node.get("min_eigen_value", min_eigen_value);
  node.get("sigma_num", sigma_num);

  node.check(voxel_size_m > 0.0 && voxel_size_m < 1e3, "voxel_size_m", "must be in (0, 1000) m");
  node.check(max_layer >= 0 && max_layer <= 6, "max_layer", "must be in [0, 6]");
  node.check(static_cast<int>(layer_init_num.size()) >= max_layer + 1, "layer_init_num",
             "needs at least max_layer + 1 = " + std::to_string(max_layer + 1) + " entries");
  int largest_init = 0;
  for (int l = 0; l <= max_layer; ++l) {
    node.check(layer_init_num[l] >= 2 && layer_init_num[l] <= 10000, "layer_init_num",
               "entries must be in [2, 10000] (a plane needs 3 points)");
    largest_init = std::max(largest_init, layer_init_num[l]);
  }
  node.check(max_points > largest_init && max_points <= 100000, "max_points",
             "must exceed every layer_init_num entry and be <= 100000");
  node.check(refit_new_points >= 1 && refit_new_points <= 60000, "refit_new_points",
             "must be in [1, 60000]");
  node.check(min_eigen_value > 0.0, "min_eigen_value", "must be > 0 (m^2)");
  node.check(sigma_num > 0.0, "sigma_num", "must be > 0");
}

int VoxelMapConfig::initNum(int layer) const {
  if (layer_init_num.empty()) return 5;
  if (layer < static_cast<int>(layer_init_num.size())) return layer_init_num[layer];
  return layer_init_num.back();
}

}  // namespace livo
