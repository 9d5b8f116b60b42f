// Backward undistortion of a LiDAR sweep to the frame time (docs/algorithms.md section 1).
#pragma once

#include "livo/common/types.hpp"
#include "livo/estimation/imu.hpp"
#include "livo/estimation/lio_update.hpp"

#include <vector>

namespace livo {

/// Moves every point of `sweep` (LiDAR frame, own time) into the IMU frame at the trace's end time:
///   p_end = R_end^T (R_t (R_il p_l + t_il) + p_t - p_end),
/// with (R_t, p_t) from the IMU trace at the point's time. Output keeps time offset, intensity, ring;
/// `p_lidar` of the output holds the IMU-frame position at the end time.
std::vector<LidarPoint> undistortToEnd(const LidarScan& sweep, const std::vector<ImuTracePoint>& trace,
                                       const Pose& T_imu_lidar);

/// Step 1c of a frame (frame_pipeline.hpp): the
/// sweep undistorted to the trace's end (undistortToEnd), voxel-downsampled at lio.downsample_m in the
/// IMU frame, uniformly subsampled beyond lio.max_points, each point with its range/bearing covariance
/// rotated into the IMU frame.
std::vector<BodyPoint> prepareScan(const LidarScan& sweep, const std::vector<ImuTracePoint>& trace,
                                   const Pose& T_imu_lidar, const LioConfig& lio);

}  // namespace livo
