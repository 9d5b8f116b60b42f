// ROS 1 bags -> LCM log: one LiDAR, one IMU and one camera topic to LIVO_LIDAR, LIVO_IMU, LIVO_CAMERA.
//
// Topics: each role takes the topic named in the options, or the only topic of a matching type (LiDAR:
// PointCloud2 or Livox CustomMsg; IMU: Imu; camera: Image or CompressedImage); "none" skips a role. Several
// candidates without a choice, a named topic that is missing or of another type, and a type whose layout
// MD5 differs from the known one are errors (before any output is written).
// Times: see ros_msgs.hpp (header stamps; LiDAR scans start at their earliest point). Events are written in
// time order through a reorder window (a scan is recorded about one scan period after it starts); an event
// older than what was already written is dropped and counted in the warnings.
// IMU acceleration unit (Livox IMUs report g): with `imu_accel_unit` Auto, the median |a| of the first
// `imu_unit_samples` samples decides: 0.7..1.3 -> g (multiplied by `gravity_m_s2`), 7..13 -> m/s^2 (kept),
// otherwise kept with a warning.
// Failures: a corrupt chunk or (unless `skip_bad_messages`) a malformed message stops the conversion; the
// events before it are kept in the log, and RosbagSummary::error says where it stopped.
#pragma once

#include "livo/datasets/conversion.hpp"
#include "livo/datasets/ros_msgs.hpp"
#include "livo/datasets/rosbag_reader.hpp"

#include <string>
#include <vector>

namespace livo {

enum class AccelUnit { Auto, G, MetresPerSecond2 };

struct RosbagOptions {
  std::string lidar_topic;  ///< "" = the only candidate, "none" = no LiDAR
  std::string imu_topic;
  std::string image_topic;
  std::string lidar_channel = "LIVO_LIDAR";
  std::string imu_channel = "LIVO_IMU";
  std::string camera_channel = "LIVO_CAMERA";
  std::string sensor;             ///< lidar_scan_t.sensor; "" = "avia" for Livox CustomMsg, else "generic"
  std::string point_time_field;   ///< RosDecodeOptions::point_time_field
  int mono16_bits = 0;            ///< RosDecodeOptions::mono16_bits
  AccelUnit imu_accel_unit = AccelUnit::Auto;
  int imu_unit_samples = 200;     ///< samples for the unit detection
  double gravity_m_s2 = 9.80665;  ///< m/s^2 per g (standard gravity)
  double reorder_window_s = 1.0;  ///< s of sensor time an event may arrive late
  double max_scan_span_s = 1.0;   ///< s; scans whose points span more are skipped (wrong time unit?)
  bool skip_bad_messages = false; ///< malformed messages: skip and count instead of stopping
  ProgressFn progress;            ///< called per message read
};

/// The topic chosen for each role ("" when none).
struct RosbagTopics {
  std::string lidar, imu, image;
  RosType lidar_type = RosType::Unknown, image_type = RosType::Unknown;
};

/// Picks the topics (rules above); throws DatasetError naming `bag_path` and the candidates.
RosbagTopics selectRosbagTopics(const std::vector<BagTopicInfo>& topics, const RosbagOptions& opt,
                                const std::string& bag_path);

/// Scale for IMU accelerations from the median |a| of samples (rule above); `note` explains the choice.
double detectAccelScale(const std::vector<double>& accel_norms, const RosbagOptions& opt, std::string& note);

struct RosbagSummary {
  ConversionSummary conversion;
  RosbagTopics topics;
  double accel_scale = 1.0;
  std::string accel_note;             ///< how the IMU unit was decided
  std::uint64_t messages_read = 0;
  std::vector<std::string> warnings;  ///< dropped late events, skipped scans or messages, ...
  std::string error;                  ///< non-empty: stopped early; the log holds what came before
  std::string describe() const;
};

/// Converts the bag into `out_log`. Throws DatasetError (and leaves no output) for problems found before
/// the first message: missing file, unreadable index, topic selection. Later read errors stop early (see
/// RosbagSummary::error).
RosbagSummary convertRosbag(const std::string& bag_path, const std::string& out_log, const RosbagOptions& opt = {});

}  // namespace livo
