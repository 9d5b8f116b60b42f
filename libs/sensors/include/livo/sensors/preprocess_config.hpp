// Configuration of the sensor preprocessing and the scan recombiner (docs/algorithms.md section 6).
//
// Keys come from the rig sections (lidar, imu, camera; config/README.md) and from the estimator
// section `preprocess`, listed below with their defaults. Only these keys are read: other modules read
// the rest of the rig sections (T_imu_lidar, fx, ...).
#pragma once

#include "livo/common/config.hpp"

namespace livo {

struct PreprocessConfig {
  // ---- lidar section ----
  double lidar_time_offset_s = 0.0;  ///< lidar.time_offset_s: added to scan stamps, s
  double blind_m = 0.8;              ///< lidar.blind_m: points closer than this are dropped, m
  double max_range_m = 100.0;        ///< lidar.max_range_m: points farther than this are dropped, m
  int point_filter_num = 1;          ///< lidar.point_filter_num: keep every n-th point that passed the
                                     ///< range filters (counted per scan, first point kept)
  // ---- imu section ----
  double imu_time_offset_s = 0.0;  ///< imu.time_offset_s: subtracted from IMU stamps, s
  double imu_rate_hz = 200.0;      ///< imu.rate_hz: nominal rate, for gap detection
  // ---- camera section ----
  /// camera.enabled: frames at image times. An absent camera section means false (LiDAR-inertial
  /// only, one frame per scan); a present section defaults to true.
  bool camera_enabled = false;
  double camera_time_offset_s = 0.0;  ///< camera.time_offset_s: added to image stamps, s

  // ---- preprocess section ----
  double min_frame_interval_s = 0.02;  ///< an image closer than this to the previous kept one is dropped
  int image_decimation = 1;            ///< keep 1 image of N (Hilti: 40 Hz -> 10 Hz with 4)
  double max_imu_gap_s = 0.0;          ///< a longer step between IMU samples is a gap; 0: 5 / imu.rate_hz
  /// A frame whose LiDAR points or IMU samples have not all arrived is emitted anyway once any stream
  /// is this far past the frame time (sensor time, never wall clock): a stopped sensor never blocks.
  double wait_timeout_s = 0.5;
  /// Camera mode: a LiDAR scan end with no image within this time after it becomes a frame without
  /// image once the data is this far past it (camera stopped or slow). <= 0 disables (pure image
  /// framing: points wait for the next image, bounded by max_buffer_s).
  double image_wait_timeout_s = 0.5;
  /// Buffered points and IMU samples older than (newest stamp - this) are dropped and counted.
  double max_buffer_s = 5.0;
  /// A stamp more than this after the previous one of its stream is held until the next message of
  /// that stream confirms it (a real gap) or not (a glitch: dropped and counted). Must exceed the
  /// period of every stream; a real gap delays that stream by one message.
  double max_time_jump_s = 1.0;
  double max_point_offset_s = 1.0;  ///< points with |time_offset_s| above this are dropped (bad time)
  /// > 0: each emitted sweep is voxel-downsampled with this leaf (downsample.hpp), m. 0: full sweep.
  double voxel_leaf_m = 0.0;

  /// Reads the keys above from the root of a rig config: lidar.{time_offset_s, blind_m, max_range_m,
  /// point_filter_num}, imu.{time_offset_s, rate_hz}, camera.{enabled, time_offset_s} and
  /// preprocess.{min_frame_interval_s, image_decimation, max_imu_gap_s, wait_timeout_s,
  /// image_wait_timeout_s, max_buffer_s, max_time_jump_s, max_point_offset_s, voxel_leaf_m}. Validates them; throws
  /// ConfigError naming the key on a bad value.
  void load(const ConfigNode& root);
  /// Checks the values (also after setting fields in code); throws std::invalid_argument.
  void validate() const;
  /// The IMU gap threshold actually used, s.
  double imuGapThresholdS() const { return max_imu_gap_s > 0.0 ? max_imu_gap_s : 5.0 / imu_rate_hz; }
};

}  // namespace livo
