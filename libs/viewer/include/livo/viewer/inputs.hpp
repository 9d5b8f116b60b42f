// What the viewer draws, as plain structs: the message adapter (libs/process viewer_node) and the run
// directory loader fill them; nothing here knows LCM.
#pragma once

#include "livo/common/so3.hpp"
#include "livo/common/types.hpp"

#include <Eigen/Core>

#include <cstdint>
#include <string>
#include <vector>

namespace livo::viewer {

/// One registered scan (LIVO_REGISTERED_SCAN): world-frame points of a frame.
struct ScanInput {
  Utime utime = 0;
  std::vector<Eigen::Vector3f> points;  ///< world frame, m
  std::vector<float> intensity;         ///< empty or one per point
  std::vector<std::int32_t> rgb;        ///< empty or one per point: 0xRRGGBB, -1 when not seen
};

/// One pose (LIVO_ODOMETRY or a trajectory.tum line).
struct PoseInput {
  Utime utime = 0;
  Pose T_world_imu = Pose::Identity();
  bool degenerate = false;  ///< odometry status bit, when known
};

/// Per-frame figures (LIVO_ESTIMATOR_STATS).
struct FrameStatsInput {
  Utime utime = 0;
  float total_ms = 0.f, lio_ms = 0.f, vio_ms = 0.f;
  float sigma_min = 0.f;
  bool degenerate = false, visual_used = false, map_timeout = false;
  /// The filter's health (estimator_stats_t.health: 0 initialising, 1 ok, 2 degraded, 3 lost) and why.
  int health = 1;
  std::string health_reason;
};

/// Map server health (LIVO_MAP_STATS).
struct MapStatsInput {
  Utime utime = 0;
  std::int64_t bytes = 0, bytes_cap = 0, local_voxels = 0, visual_points = 0;
};

}  // namespace livo::viewer
