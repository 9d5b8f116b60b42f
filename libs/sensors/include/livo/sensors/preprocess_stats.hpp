// Counters of the sensor preprocessing: every input item is either used or counted under one reason.
//
// Point conservation (checked by the tests):
//   points_in = points_nan + points_bad_time + points_blind + points_range + points_decimated
//             + points_out_of_order + points_late + points_overflow + points_voxel_merged
//             + points_emitted + (points still buffered, Recombiner::pendingPoints()).
// Images: images_in = images_used + imagesDropped() + (images still buffered).
#pragma once

#include <cstdint>
#include <string>

namespace livo {

struct PreprocessStats {
  using Count = std::uint64_t;

  // ---- frames ----
  Count frames = 0;
  Count frames_without_image = 0;     ///< LiDAR-only mode, or camera mode after image_wait_timeout_s
  Count empty_sweeps = 0;             ///< frames emitted with no point (LiDAR stopped or blank)
  Count frames_lidar_incomplete = 0;  ///< emitted on timeout before the LiDAR reached the frame time
  Count frames_imu_incomplete = 0;    ///< IMU samples do not bracket [sweep start, frame time]

  // ---- images ----
  Count images_in = 0;
  Count images_used = 0;
  Count images_ignored = 0;       ///< camera disabled
  Count images_invalid = 0;       ///< not Gray8, or size / stride / data length inconsistent
  Count images_stale = 0;         ///< stamp at or before the last emitted frame
  Count images_out_of_order = 0;  ///< stamp at or before the previous image (backward jump, duplicate)
  Count images_decimated = 0;     ///< image_decimation
  Count images_too_close = 0;     ///< closer than min_frame_interval_s to the previous kept image
  Count images_no_lidar = 0;      ///< before the first LiDAR point, or no LiDAR at all within the timeout
  Count images_overflow = 0;      ///< still waiting after max_buffer_s (nextFrame not called)
  Count images_glitches = 0;      ///< unconfirmed forward stamp jump (max_time_jump_s)
  Count imagesDropped() const {
    return images_ignored + images_invalid + images_stale + images_out_of_order + images_decimated +
           images_too_close + images_no_lidar + images_overflow + images_glitches;
  }

  // ---- IMU ----
  Count imu_in = 0;
  Count imu_invalid = 0;       ///< non-finite values
  Count imu_out_of_order = 0;  ///< stamp before the newest sample (dropped)
  Count imu_duplicates = 0;    ///< stamp equal to the newest sample (dropped)
  Count imu_gaps = 0;          ///< steps longer than PreprocessConfig::imuGapThresholdS()
  double imu_max_gap_s = 0.0;  ///< largest step between consecutive accepted samples
  Count imu_overflow = 0;      ///< dropped by max_buffer_s while still needed
  Count imu_glitches = 0;      ///< unconfirmed forward stamp jump (max_time_jump_s)

  // ---- scans and points ----
  Count scans_in = 0;
  Count scans_out_of_order = 0;  ///< start stamp at or before the previous scan's (whole scan dropped)
  Count scans_empty = 0;         ///< no point left after filtering
  Count scans_glitches = 0;      ///< unconfirmed forward stamp jump (whole scan dropped)
  Count forward_jumps = 0;       ///< confirmed forward stamp jumps, all streams (data kept)
  Count points_in = 0;
  Count points_nan = 0;             ///< non-finite coordinates or time offset
  Count points_bad_time = 0;        ///< |time_offset_s| > max_point_offset_s
  Count points_blind = 0;           ///< closer than blind_m
  Count points_range = 0;           ///< farther than max_range_m
  Count points_decimated = 0;       ///< point_filter_num
  Count points_out_of_order = 0;    ///< in scans dropped as out of order or as glitches
  Count points_late = 0;            ///< time at or before a frame already emitted
  Count points_overflow = 0;        ///< dropped by max_buffer_s
  Count points_voxel_merged = 0;    ///< removed by the sweep voxel filter (voxel_leaf_m)
  Count points_emitted = 0;         ///< in emitted sweeps

  Count bufferOverflowDrops() const { return points_overflow + imu_overflow + images_overflow; }
  /// Multi-line human-readable report of all counters.
  std::string summary() const;
};

}  // namespace livo
