#include "livo/map/visual_map_config.hpp"

#include <functional>
#include <stdexcept>
#include <string>

namespace livo {

namespace {

// Calls bad(key, what) for the first invalid field; one list shared by load() and validate().
void checkFields(const VisualMapConfig& c, const std::function<void(const char*, const char*)>& bad) {
  auto check = [&](bool ok, const char* key, const char* what) {
    if (!ok) bad(key, what);
  };
  check(c.voxel_size_m > 0.0 && c.voxel_size_m < 1e3, "voxel_size_m", "must be in (0, 1000) m");
  check(c.grid_cell_px >= 4 && c.grid_cell_px <= 4096, "grid_cell_px", "must be in [4, 4096] px");
  check(c.border_px >= VisualMapConfig::kMinBorderPx && c.border_px < 1e4, "border_px",
        "must be >= 28 px (every patch sample of every level inside the image)");
  check(c.min_depth_m > 0.0 && c.min_depth_m < 1e3, "min_depth_m", "must be in (0, 1000) m");
  check(c.min_shi_tomasi >= 0.0, "min_shi_tomasi", "must be >= 0");
  check(c.occlusion_window_px >= 0 && c.occlusion_window_px <= 64, "occlusion_window_px", "must be in [0, 64] px");
  check(c.occlusion_depth_m > 0.0, "occlusion_depth_m", "must be > 0 m");
  check(c.max_observations >= 2 && c.max_observations <= 1000, "max_observations", "must be in [2, 1000]");
  check(c.new_obs_min_translation_m > 0.0, "new_obs_min_translation_m", "must be > 0 m");
  check(c.new_obs_min_angle_deg > 0.0 && c.new_obs_min_angle_deg < 180.0, "new_obs_min_angle_deg",
        "must be in (0, 180) deg");
  check(c.new_obs_min_pixel_shift_px > 0.0, "new_obs_min_pixel_shift_px", "must be > 0 px");
  check(c.refine_min_observations >= 1, "refine_min_observations", "must be >= 1");
  check(c.converge_min_observations >= 1, "converge_min_observations", "must be >= 1");
  check(c.normal_converge > 0.0 && c.normal_converge < 2.0, "normal_converge", "must be in (0, 2)");
  check(c.max_bad_updates >= 0, "max_bad_updates", "must be >= 0");
}

}  // namespace

void VisualMapConfig::load(const ConfigNode& node) {
  node.get("voxel_size_m", voxel_size_m);
  node.get("grid_cell_px", grid_cell_px);
  node.get("border_px", border_px);
  node.get("min_depth_m", min_depth_m);
  node.get("min_shi_tomasi", min_shi_tomasi);
  node.get("occlusion_window_px", occlusion_window_px);
  node.get("occlusion_depth_m", occlusion_depth_m);
  node.get("max_observations", max_observations);
  node.get("new_obs_min_translation_m", new_obs_min_translation_m);
  node.get("new_obs_min_angle_deg", new_obs_min_angle_deg);
  node.get("new_obs_min_pixel_shift_px", new_obs_min_pixel_shift_px);
  node.get("refine_min_observations", refine_min_observations);
  node.get("converge_min_observations", converge_min_observations);
  node.get("normal_converge", normal_converge);
  node.get("max_bad_updates", max_bad_updates);
  checkFields(*this, [&](const char* key, const char* what) { node.fail(key, what); });
}

void VisualMapConfig::validate() const {
  checkFields(*this, [](const char* key, const char* what) {
    throw std::invalid_argument(std::string("VisualMapConfig: ") + key + ": " + what);
  });
}

}  // namespace livo
