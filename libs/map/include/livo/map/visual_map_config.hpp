// Configuration of the visual map (docs/algorithms.md sections 4-5; read from the rig config's `vio`
// section). Values follow FAST-LIVO2 where it has them, scaled down where this project keeps less
// (max_observations 8 instead of 30, so the refinement/convergence counts are scaled with it).
#pragma once

#include "livo/common/config.hpp"
#include "livo/map/visual_point.hpp"

namespace livo {

struct VisualMapConfig {
  /// Smallest border (pixels, processed image scale) that keeps every sample of every crop level
  /// inside the image, with one extra sample for central-difference gradients:
  /// (kCrop/2 + 1) * 2^(kLevels-1) = 7 * 4 = 28 px (fixes docs/algorithms.md section 8 "Crashes" #69).
  static constexpr double kMinBorderPx =
      double((PatchPyramid::kCrop / 2 + 1) * (1 << (PatchPyramid::kLevels - 1)));

  double voxel_size_m = 0.5;  ///< edge of a visual root voxel, m (FAST-LIVO2 hard-codes 0.5)
  int grid_cell_px = 30;      ///< side of a selection grid cell, px at the processed scale (FAST-LIVO2: height/17)
  double border_px = kMinBorderPx;  ///< points closer than this to the image edge are not used, px

  // Creation (docs/algorithms.md 5.1).
  double min_depth_m = 0.1;        ///< points must lie at least this far in front of the camera (z), m
  double min_shi_tomasi = 0.0;     ///< a new point needs a Shi-Tomasi score above this, gray^2 (mean over 8x8)

  // Retrieval (docs/algorithms.md 4.2).
  int occlusion_window_px = 4;     ///< half side of the window searched in the sparse depth image, px
  double occlusion_depth_m = 0.5;  ///< occluded when a scan depth in the window is closer by more, m

  // Observations (docs/algorithms.md 5.2).
  int max_observations = 8;                 ///< observations kept per point (FAST-LIVO2: 30)
  double new_obs_min_translation_m = 0.5;   ///< new observation when the camera moved more than this, m
  double new_obs_min_angle_deg = 17.1887;   ///< ... or the view ray turned more than this, deg (0.3 rad)
  double new_obs_min_pixel_shift_px = 40.0; ///< ... or the pixel moved more than this, px

  // Reference selection and normal refinement (docs/algorithms.md 5.3).
  int refine_min_observations = 3;    ///< the LiDAR normal is looked up from this many observations on (FAST-LIVO2: > 5)
  int converge_min_observations = 6;  ///< converged needs at least this many observations (FAST-LIVO2: > 10)
  double normal_converge = 1e-4;      ///< converged when |n_new - n_old| is below this (unit vectors)

  // Outliers (docs/algorithms.md 5.5).
  int max_bad_updates = 3;  ///< a point with more consecutive bad photometric updates than this is removed

  /// Reads the keys above (same names) from `node` (the `vio` section) and validates them; throws
  /// ConfigError naming the key on a bad value.
  void load(const ConfigNode& node);
  /// Throws std::invalid_argument naming the first invalid field (used by VisualMap's constructor).
  void validate() const;
};

}  // namespace livo
