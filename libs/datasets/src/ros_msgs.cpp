// ROS 1 message types known to the bag converter, and the IMU decoder.
#include "livo/datasets/ros_msgs.hpp"

#include "ros_buffer.hpp"

#include <cmath>

namespace livo {

RosType rosTypeOf(const std::string& datatype) {
  if (datatype == "sensor_msgs/Imu") return RosType::Imu;
  if (datatype == "sensor_msgs/PointCloud2") return RosType::PointCloud2;
  if (datatype == "livox_ros_driver/CustomMsg" || datatype == "livox_ros_driver2/CustomMsg")
    return RosType::LivoxCustomMsg;
  if (datatype == "sensor_msgs/Image") return RosType::Image;
  if (datatype == "sensor_msgs/CompressedImage") return RosType::CompressedImage;
  return RosType::Unknown;
}

const char* rosLayoutMd5(RosType t) {
  // MD5 sums of the message definitions (ROS genmsg rule: the definition text with every nested type
  // replaced by its own MD5). The Livox one covers both driver versions (same definition text).
  switch (t) {
    case RosType::Imu: return "6a62c6daae103f4ff57a132d6f95cec2";
    case RosType::PointCloud2: return "1158d486dd51d683ce2f1be655c3c181";
    case RosType::LivoxCustomMsg: return "e4d6829bdfe657cb6c21a746c86b21a6";
    case RosType::Image: return "060021388200f6f0f447d0fcd9c64743";
    case RosType::CompressedImage: return "8f7a12909da2c9d3332d540a0977563f";
    case RosType::Unknown: break;
  }
  return "";
}

const char* rosSupportedTypes() {
  return "sensor_msgs/Imu, sensor_msgs/PointCloud2, livox_ros_driver/CustomMsg, livox_ros_driver2/CustomMsg, "
         "sensor_msgs/Image, sensor_msgs/CompressedImage";
}

ImuSample decodeRosImu(const std::uint8_t* data, std::size_t size) {
  // Header, orientation (4 float64), orientation_covariance (9), angular_velocity (3),
  // angular_velocity_covariance (9), linear_acceleration (3), linear_acceleration_covariance (9).
  RosBuffer b(data, size, "sensor_msgs/Imu");
  ImuSample s;
  s.utime = nsToUtimeRound(b.header());
  b.take(13 * sizeof(double), "orientation");
  const char* gyro_names[3] = {"angular_velocity.x", "angular_velocity.y", "angular_velocity.z"};
  const char* acc_names[3] = {"linear_acceleration.x", "linear_acceleration.y", "linear_acceleration.z"};
  for (int i = 0; i < 3; ++i) s.gyro[i] = b.get<double>(gyro_names[i]);
  b.take(9 * sizeof(double), "angular_velocity_covariance");
  for (int i = 0; i < 3; ++i) s.accel[i] = b.get<double>(acc_names[i]);
  b.take(9 * sizeof(double), "linear_acceleration_covariance");
  b.finish();
  for (int i = 0; i < 3; ++i) {
    if (!std::isfinite(s.gyro[i])) b.fail(gyro_names[i], "not finite");
    if (!std::isfinite(s.accel[i])) b.fail(acc_names[i], "not finite");
  }
  return s;
}

}  // namespace livo
