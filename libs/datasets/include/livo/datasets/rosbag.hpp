// ROS 1 bags -> LCM log: one LiDAR, one IMU and one camera topic to LIVO_LIDAR, LIVO_IMU, LIVO_CAMERA.
//
// Topics, message decoding, scan rules and the IMU acceleration unit: ros_input.hpp (the rules the live
// bridge livo-ros-bridge applies too). Here, several candidates without a choice, a named topic that is
// missing or of another type, and a type whose layout MD5 differs from the known one are errors (before
// any output is written), and the IMU unit is decided from the bag's first IMU samples before the rest.
// Times: see ros_msgs.hpp (header stamps; LiDAR scans start at their earliest point). Events are written in
// time order through a reorder window (a scan is recorded about one scan period after it starts); an event
// older than what was already written is dropped and counted in the warnings.
// Failures: a corrupt chunk or (unless `skip_bad_messages`) a malformed message stops the conversion; the
// events before it are kept in the log, and RosbagSummary::error says where it stopped.
#pragma once

#include "livo/datasets/conversion.hpp"
#include "livo/datasets/ros_input.hpp"
#include "livo/datasets/ros_msgs.hpp"
#include "livo/datasets/rosbag_reader.hpp"

#include <string>
#include <vector>

namespace livo {

/// The bag converter's options: the ROS input's (topics, decoding, IMU unit) and the output's.
struct RosbagOptions : RosInputOptions {
  std::string lidar_channel = "LIVO_LIDAR";
  std::string imu_channel = "LIVO_IMU";
  std::string camera_channel = "LIVO_CAMERA";
  double reorder_window_s = 1.0;  ///< s of sensor time an event may arrive late
  bool skip_bad_messages = false; ///< malformed messages: skip and count instead of stopping
  ProgressFn progress;            ///< called per message read
};

/// The topic chosen for each role ("" when none).
struct RosbagTopics {
  std::string lidar, imu, image;
  RosType lidar_type = RosType::Unknown, image_type = RosType::Unknown;
};

/// Picks the topics (chooseRosTopic, then the layout MD5s); throws DatasetError naming `bag_path` and the
/// candidates for any problem.
RosbagTopics selectRosbagTopics(const std::vector<BagTopicInfo>& topics, const RosInputOptions& opt,
                                const std::string& bag_path);

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
RosbagSummary convertRosbag(const std::string& bag_path, const std::string& out_log, const RosbagOptions& opt = RosbagOptions());

}  // namespace livo
