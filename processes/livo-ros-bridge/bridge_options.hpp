// The settings of livo-ros-bridge (command line in main.cpp; the LCM channel names come from the config's
// `channels` section).
#pragma once

#include "livo/datasets/ros_input.hpp"
#include "livo/io/channels.hpp"

#include <cstdint>
#include <string>

namespace livo_bridge {

struct BridgeOptions {
  livo::RosInputOptions input;  ///< topics and decoding: the same options as livo-convert rosbag
  livo::ChannelConfig channels;
  std::string lcm_url;          ///< resolved (flag, $LCM_DEFAULT_URL, suite default)
  std::string node_name = "livo_ros_bridge";
  std::string ros_master;       ///< "" = roscpp's default ($ROS_MASTER_URI, else http://localhost:11311)
  std::string world_frame = "world";
  std::string body_frame = "body";
  std::string topic_prefix = "/livo";  ///< <prefix>/odometry, <prefix>/registered_scan, <prefix>/map
  int queue = 10;                ///< messages per LiDAR / camera topic and per LCM output channel
  int imu_queue = 400;           ///< messages per IMU topic (2 s at 200 Hz)
  double map_voxel_m = 0.2;      ///< m, one map point per voxel
  std::int64_t map_max_points = 300'000;  ///< above it the map's voxel size doubles
  double map_period_s = 1.0;     ///< s of message time between two map messages
  double stats_s = 0;            ///< s between two statistics reports on stderr (0: the summary at exit only)
  double master_poll_s = 0.5;    ///< s between two checks of the ROS master and of the topics
};

}  // namespace livo_bridge
