// Rig config for livo-run matching a scenario (schema: config/README.md).
#include "livo/sim/simulator.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <ostream>
#include <string>

namespace livo::sim {

namespace {

std::string num(double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.10g", v);
  std::string s = buf;
  if (s.find_first_of(".eEn") == std::string::npos) s += ".0";  // keep YAML floats recognisable
  return s;
}

std::string pose(const Pose& T) {
  const auto a = poseToArray(T);
  std::string s = "[";
  for (std::size_t i = 0; i < a.size(); ++i) s += (i ? ", " : "") + num(std::abs(a[i]) < 1e-15 ? 0.0 : a[i]);
  return s + "]";
}

}  // namespace

void writeRigConfig(const SimScenario& sc, std::ostream& out) {
  const bool outdoor = sc.environmentOrDefault() == "outdoor";
  // The start's window follows the IMU alone (half a second of samples), never the scenario's rest: a
  // rig config knows its sensors, not how long the next run stands still.
  const int init_samples = std::clamp(static_cast<int>(std::lround(0.5 * sc.imu.rate_hz)), 20, 400);
  const std::string file = sc.source.substr(sc.source.find_last_of('/') + 1);
  out << "# Rig config written by livo-sim --rig for the scenario " << file << " (config/sim/).\n"
      << "# Schema: config/README.md. Calibration and noise are the simulated sensors' true values\n"
      << "# (noise sigmas with small floors so that covariances stay positive).\n"
      << "environment: " << sc.environmentOrDefault() << "\n\n"
      << "imu:\n"
      << "  rate_hz: " << num(sc.imu.rate_hz) << "\n"
      << "  gyro_noise: " << num(sc.imu.gyro_noise) << "\n"
      << "  accel_noise: " << num(sc.imu.accel_noise) << "\n"
      << "  gyro_bias_walk: " << num(sc.imu.gyro_bias_walk) << "\n"
      << "  accel_bias_walk: " << num(sc.imu.accel_bias_walk) << "\n"
      << "  time_offset_s: 0.0\n"
      << "  init_samples: " << init_samples << "\n"
      << "\n"
      << "lidar:\n"
      << "  model: " << sc.lidar.model << "\n"
      << "  T_imu_lidar: " << pose(sc.extrinsics.T_imu_lidar) << "\n"
      << "  time_offset_s: 0.0\n"
      << "  blind_m: " << num(sc.lidar.blind_m) << "\n"
      << "  max_range_m: " << num(sc.lidar.max_range_m) << "\n"
      << "  point_filter_num: " << (sc.lidar.model == "spinning32" ? 2 : 1) << "\n"
      << "  range_noise_m: " << num(std::max(sc.lidar.range_noise_m, 0.005)) << "\n"
      << "  beam_noise_deg: " << num(std::max(sc.lidar.beam_noise_deg, 0.01)) << "\n\n";
  if (sc.camera.enabled) {
    const auto& c = sc.camera;
    out << "camera:\n"
        << "  enabled: true\n"
        << "  model: " << c.model << "\n"
        << "  width: " << c.width << "\n"
        << "  height: " << c.height << "\n"
        << "  fx: " << num(c.fx) << "\n"
        << "  fy: " << num(c.fy) << "\n"
        << "  cx: " << num(c.cx) << "\n"
        << "  cy: " << num(c.cy) << "\n"
        << "  distortion: [" << num(c.distortion[0]) << ", " << num(c.distortion[1]) << ", " << num(c.distortion[2])
        << ", " << num(c.distortion[3]) << "]\n"
        << "  scale: 1.0\n"
        << "  T_imu_camera: " << pose(sc.extrinsics.T_imu_camera) << "\n"
        << "  time_offset_s: " << num(c.stamp_delay_s > 0.0 ? -c.stamp_delay_s : 0.0) << "\n"  // capture = stamp + offset
        << "  rate_hz: " << num(c.rate_hz) << "\n"
        << (c.vignetting > 0.0 ? "  vignetting: " + num(c.vignetting) + "\n" : std::string())
        << "  pixel_noise: " << num(std::max(c.pixel_noise, 1.0)) << "\n\n";
  } else {
    out << "camera:\n  enabled: false\n\n";
  }
  out << "selector:\n"
      << "  degeneracy_threshold: 0.15\n"
      << "  degenerate_frames: 3\n"
      << "  tau_translation_m: " << (outdoor ? "2.0" : "1.0") << "\n"
      << "  tau_rotation_deg: 60.0\n";
  if (sc.rig_map.any()) {
    out << "\nmap:  # scaled with the scenario (its rig_map section)\n";
    for (const auto& [key, field] : RigMapConfig::kKeys)
      if (sc.rig_map.*field > 0) out << "  " << key << ": " << num(sc.rig_map.*field) << "\n";
  }
}

}  // namespace livo::sim
