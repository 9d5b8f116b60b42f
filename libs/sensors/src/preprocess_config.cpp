#include "livo/sensors/preprocess_config.hpp"

#include <cmath>
#include <stdexcept>
#include <string>
#include <utility>

namespace livo {

namespace {

/// First invalid value as (dotted key, reason); empty key when all are valid.
std::pair<std::string, std::string> firstProblem(const PreprocessConfig& c) {
  auto finite = [](double v) { return std::isfinite(v); };
  if (!finite(c.lidar_time_offset_s) || std::abs(c.lidar_time_offset_s) > 1e4)
    return {"lidar.time_offset_s", "must be a finite offset below 1e4 s"};
  if (!finite(c.blind_m) || c.blind_m < 0.0) return {"lidar.blind_m", "must be >= 0 m"};
  if (!finite(c.max_range_m) || c.max_range_m <= c.blind_m)
    return {"lidar.max_range_m", "must be finite and > lidar.blind_m"};
  if (c.point_filter_num < 1 || c.point_filter_num > 1000) return {"lidar.point_filter_num", "must be in [1, 1000]"};
  if (!finite(c.imu_time_offset_s) || std::abs(c.imu_time_offset_s) > 1e4)
    return {"imu.time_offset_s", "must be a finite offset below 1e4 s"};
  if (!finite(c.imu_rate_hz) || c.imu_rate_hz <= 0.0 || c.imu_rate_hz > 1e5)
    return {"imu.rate_hz", "must be in (0, 1e5] Hz"};
  if (!finite(c.camera_time_offset_s) || std::abs(c.camera_time_offset_s) > 1e4)
    return {"camera.time_offset_s", "must be a finite offset below 1e4 s"};
  if (!finite(c.min_frame_interval_s) || c.min_frame_interval_s < 0.0 || c.min_frame_interval_s > 10.0)
    return {"preprocess.min_frame_interval_s", "must be in [0, 10] s"};
  if (c.image_decimation < 1 || c.image_decimation > 1000) return {"preprocess.image_decimation", "must be in [1, 1000]"};
  if (!finite(c.max_imu_gap_s) || c.max_imu_gap_s < 0.0) return {"preprocess.max_imu_gap_s", "must be >= 0 s (0: automatic)"};
  if (!finite(c.wait_timeout_s) || c.wait_timeout_s <= 0.0 || c.wait_timeout_s > 60.0)
    return {"preprocess.wait_timeout_s", "must be in (0, 60] s"};
  if (!finite(c.image_wait_timeout_s) || c.image_wait_timeout_s > 60.0)
    return {"preprocess.image_wait_timeout_s", "must be <= 60 s (<= 0 disables)"};
  if (!finite(c.max_buffer_s) || c.max_buffer_s <= c.wait_timeout_s || c.max_buffer_s <= c.image_wait_timeout_s ||
      c.max_buffer_s > 3600.0)
    return {"preprocess.max_buffer_s", "must exceed wait_timeout_s and image_wait_timeout_s, and be <= 3600 s"};
  if (!finite(c.max_time_jump_s) || c.max_time_jump_s <= 0.0 || c.max_time_jump_s > 3600.0)
    return {"preprocess.max_time_jump_s", "must be in (0, 3600] s"};
  if (!finite(c.max_point_offset_s) || c.max_point_offset_s <= 0.0 || c.max_point_offset_s > 60.0)
    return {"preprocess.max_point_offset_s", "must be in (0, 60] s"};
  if (!finite(c.voxel_leaf_m) || c.voxel_leaf_m < 0.0 || c.voxel_leaf_m > 100.0)
    return {"preprocess.voxel_leaf_m", "must be in [0, 100] m (0: off)"};
  return {};
}

}  // namespace

void PreprocessConfig::load(const ConfigNode& root) {
  const ConfigNode lidar = root.section("lidar");
  lidar.get("time_offset_s", lidar_time_offset_s);
  lidar.get("blind_m", blind_m);
  lidar.get("max_range_m", max_range_m);
  lidar.get("point_filter_num", point_filter_num);

  const ConfigNode imu = root.section("imu");
  imu.get("time_offset_s", imu_time_offset_s);
  imu.get("rate_hz", imu_rate_hz);

  if (root.has("camera")) {
    const ConfigNode camera = root.section("camera");
    camera_enabled = true;
    camera.get("enabled", camera_enabled);
    camera.get("time_offset_s", camera_time_offset_s);
  }

  const ConfigNode pre = root.section("preprocess");
  pre.get("min_frame_interval_s", min_frame_interval_s);
  pre.get("image_decimation", image_decimation);
  pre.get("max_imu_gap_s", max_imu_gap_s);
  pre.get("wait_timeout_s", wait_timeout_s);
  pre.get("image_wait_timeout_s", image_wait_timeout_s);
  pre.get("max_buffer_s", max_buffer_s);
  pre.get("max_time_jump_s", max_time_jump_s);
  pre.get("max_point_offset_s", max_point_offset_s);
  pre.get("voxel_leaf_m", voxel_leaf_m);

  const auto problem = firstProblem(*this);
  if (!problem.first.empty()) root.fail(problem.first, problem.second);
}

void PreprocessConfig::validate() const {
  const auto problem = firstProblem(*this);
  if (!problem.first.empty())
    throw std::invalid_argument("PreprocessConfig: " + problem.first + ": " + problem.second);
}

}  // namespace livo
