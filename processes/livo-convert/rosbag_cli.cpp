// livo-convert rosbag: options and the run (conversion summary on stdout, progress and errors on stderr).
#include "cli.hpp"

#include <iostream>

namespace livo_convert {

void addCommonOptions(livo::CommandLine& cl, CommonArgs& a, const std::string& input_metavar,
                      const std::string& input_help) {
  cl.positional(input_metavar, &a.in, input_help);
  cl.text("--out", &a.out, "LOG.lcm",
          "output log (overwritten; removed again if the conversion fails, except a bag conversion stopped by a "
          "corrupt chunk, which keeps the events before it)")
      .required();
  livo::addProgressOption(cl, &a.progress);
  cl.flag("--quiet", &a.quiet, "no progress line on stderr");
}

void addRosbagOptions(livo::CommandLine& cl, livo::RosbagOptions& opt) {
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
            {{"auto", livo::AccelUnit::Auto}, {"g", livo::AccelUnit::G}, {"mps2", livo::AccelUnit::MetresPerSecond2}},
            "IMU acceleration unit; auto: median |a| of the first 200 samples in 0.7..1.3 means g, converted with "
            "--gravity");
  cl.number("--gravity", &opt.gravity_m_s2, "G", "per g", 0.0, true).unit("m/s^2");
  cl.integer("--mono16-bits", &opt.mono16_bits, "B",
             "convert mono16/16UC1 images to GRAY8 keeping the top 8 of B significant bits", 9, 16)
      .defaultText("keep GRAY16");
  cl.number("--reorder-window", &opt.reorder_window_s, "S", "sensor time an event may arrive late", 0.0).unit("s");
  cl.number("--max-scan-span", &opt.max_scan_span_s, "S", "skip scans whose points span more than S", 0.0, true)
      .unit("s");
  cl.flag("--skip-bad", &opt.skip_bad_messages, "skip malformed messages (counted) instead of stopping at the first");
  cl.text("--imu-channel", &opt.imu_channel, "CH", "output channel of the IMU");
  cl.text("--camera-channel", &opt.camera_channel, "CH", "output channel of the images");
  cl.text("--lidar-channel", &opt.lidar_channel, "CH", "output channel of the scans");
}

int runRosbag(const std::string& bag, const std::string& out, livo::RosbagOptions opt, livo::ProgressMode progress) {
  if (!livo::rosbagSupported()) {
    std::cerr << "livo-convert: error: this livo-convert was built without ROS bag support (librosbag-storage-dev "
                 "was not found, or LIVO_WITH_ROSBAG was OFF, when the build was configured); install it (scripts/setup does) and rebuild\n";
    return livo::kExitRunError;
  }
  opt.progress = progressLine(progress, "messages");
  const livo::RosbagSummary s = livo::convertRosbag(bag, out, opt);
  opt.progress = nullptr;  // ends the progress line before the summary and errors
  std::cout << "livo-convert rosbag: " << s.describe();
  if (!s.error.empty()) {
    std::cerr << "livo-convert: error: " << s.error << "\n"
              << "livo-convert: " << out << " keeps the " << s.conversion.events
              << " events converted before the error\n";
    return livo::kExitRunError;
  }
  return livo::kExitOk;
}

}  // namespace livo_convert
