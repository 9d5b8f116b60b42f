#include "livo/sensors/camera_config.hpp"

#include <cmath>

namespace livo {

void CameraConfig::load(const ConfigNode& root, std::optional<bool> camera_enabled) {
  if (!root.has("camera")) {
    enabled = false;
    return;
  }
  const ConfigNode n = root.section("camera");
  enabled = camera_enabled.value_or(true);
  if (!camera_enabled) n.get("enabled", enabled);
  readMode(n, "model", model);
  n.get("scale", scale).get("pixel_noise", pixel_noise).get("distortion", distortion);
  n.get("vignetting", vignetting);
  n.get("rate_hz", rate_hz).get("estimate_time_offset", estimate_time_offset);
  n.get("time_offset_sigma_s", time_offset_sigma_s);
  n.check(rate_hz > 0 && rate_hz <= 1000, "rate_hz", "must be in (0, 1000] (the nominal image rate)");
  n.check(std::isfinite(time_offset_sigma_s) && time_offset_sigma_s > 0 && time_offset_sigma_s <= 0.5 / rate_hz,
          "time_offset_sigma_s", "must be > 0 and at most half the image interval (0.5 / camera.rate_hz s)");
  n.check(pixel_noise > 0, "pixel_noise", "must be > 0");
  if (!enabled) {
    // A disabled camera may still carry its calibration: read it without requiring it.
    n.get("width", width).get("height", height).get("fx", fx).get("fy", fy).get("cx", cx).get("cy", cy);
    n.get("T_imu_camera", T_imu_camera);
    return;
  }
  n.require("width", width).require("height", height);
  n.require("fx", fx).require("fy", fy).require("cx", cx).require("cy", cy);
  n.require("T_imu_camera", T_imu_camera);
  n.check(width > 0 && width <= 16384, "width", "must be in 1..16384");
  n.check(height > 0 && height <= 16384, "height", "must be in 1..16384");
  n.check(fx > 0, "fx", "must be > 0");
  n.check(fy > 0, "fy", "must be > 0");
  n.check(distortion.empty() || distortion.size() == 4, "distortion", "needs 4 coefficients (or none)");
  n.check(scale > 0 && scale <= 1.0, "scale", "must be in (0, 1]");
  n.check(vignetting >= 0 && vignetting < 1, "vignetting", "must be in [0, 1) (the fall-off 1 - k r^2 at the corner)");
}

}  // namespace livo
