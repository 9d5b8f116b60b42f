// The command-line options of a ROS input (topics, decoding, IMU unit), the same for `livo-convert rosbag`
// and `livo-ros-bridge`.
#pragma once

#include "livo/datasets/ros_input.hpp"

namespace livo {

class CommandLine;

/// Registers --lidar-topic, --imu-topic, --image-topic, --sensor, --point-time-field, --imu-accel-unit,
/// --gravity, --mono16-bits and --max-scan-span on `cl`, filling `opt`.
void addRosInputOptions(CommandLine& cl, RosInputOptions& opt);

}  // namespace livo
