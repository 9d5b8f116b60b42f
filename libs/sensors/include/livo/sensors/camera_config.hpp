// Camera calibration from the rig config's `camera` section (config/README.md).
#pragma once

#include "livo/common/config.hpp"
#include "livo/common/modes.hpp"
#include "livo/common/so3.hpp"

#include <optional>
#include <string>
#include <vector>

namespace livo {

struct CameraConfig {
  bool enabled = false;          ///< absent section: no camera
  CameraKind model = CameraKind::Pinhole; ///< pinhole (radtan k1 k2 p1 p2) | equidistant (Kannala-Brandt k1..k4)
  int width = 0, height = 0;     ///< pixels (required when enabled)
  double fx = 0, fy = 0, cx = 0, cy = 0;  ///< pixels (required when enabled)
  std::vector<double> distortion;  ///< 4 coefficients (or empty = none)
  double scale = 1.0;            ///< image and intrinsics scale used by the visual update (0 < scale <= 1)
  Pose T_imu_camera = Pose::Identity();  ///< camera pose in the IMU frame (required when enabled)
  double pixel_noise = 3.0;      ///< photometric noise sigma, gray levels
  double vignetting = 0.0;       ///< k of the fall-off 1 - k r^2, divided out of every image (vignetting.hpp)
  double rate_hz = 10.0;         ///< nominal image rate (the time offset's bounds; the selector's)
  /// Online camera-IMU time offset in the photometric update, prior sigma time_offset_sigma_s (below half
  /// the image interval).
  bool estimate_time_offset = false;
  double time_offset_sigma_s = 0.005;

  /// Reads the `camera` section of a rig config; keys owned by the preprocessing (time_offset_s) are
  /// read there. `camera_enabled`: camera.enabled as the preprocessing's config read it (the pipeline
  /// loads that first), not read again; absent, it is read here. Throws ConfigError naming the key when
  /// a required one is missing or invalid.
  void load(const ConfigNode& root, std::optional<bool> camera_enabled = std::nullopt);
};

}  // namespace livo
