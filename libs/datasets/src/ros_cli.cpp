// The command-line options of a ROS input (ros_cli.hpp).
#include "livo/datasets/ros_cli.hpp"

#include "livo/cli/command_line.hpp"

namespace livo {

void addRosInputOptions(CommandLine& cl, RosInputOptions& opt) {
  const char* topic_default = "the only topic of a matching type; \"none\" skips the role";
  cl.text("--lidar-topic", &opt.lidar_topic, "T", "sensor_msgs/PointCloud2 or livox_ros_driver(2)/CustomMsg topic")
      .defaultText(topic_default);
  cl.text("--imu-topic", &opt.imu_topic, "T", "sensor_msgs/Imu topic").defaultText(topic_default);
  cl.text("--image-topic", &opt.image_topic, "T", "sensor_msgs/Image or sensor_msgs/CompressedImage topic")
      .defaultText(topic_default);
  cl.text("--sensor", &opt.sensor, "NAME", "lidar_scan_t.sensor").defaultText("avia for Livox CustomMsg, else generic");
  cl.text("--point-time-field", &opt.point_time_field, "F",
          "PointCloud2 per-point time field, or none (integer fields are ns, floating ones s; values of 1e5 s and "
          "more are absolute times, smaller ones offsets from the header stamp)")
      .defaultText("the first of time, t, timestamp, offset_time");
  cl.choice("--imu-accel-unit", &opt.imu_accel_unit,
            {{"auto", AccelUnit::Auto}, {"g", AccelUnit::G}, {"mps2", AccelUnit::MetresPerSecond2}},
            "IMU acceleration unit; auto: median |a| of the first 200 samples in 0.7..1.3 means g, converted with "
            "--gravity");
  cl.number("--gravity", &opt.gravity_m_s2, "G", "per g", 0.0, true).unit("m/s^2");
  cl.integer("--mono16-bits", &opt.mono16_bits, "B",
             "convert mono16/16UC1 images to GRAY8 keeping the top 8 of B significant bits", 9, 16)
      .defaultText("keep GRAY16");
  cl.number("--max-scan-span", &opt.max_scan_span_s, "S", "skip scans whose points span more than S", 0.0, true)
      .unit("s");
}

}  // namespace livo
