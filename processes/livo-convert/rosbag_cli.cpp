// livo-convert rosbag: options and the run (conversion summary on stdout, progress and errors on stderr).
#include "cli.hpp"

#include "livo/datasets/ros_cli.hpp"

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
  livo::addRosInputOptions(cl, opt);  // the options livo-ros-bridge shares
  cl.number("--reorder-window", &opt.reorder_window_s, "S", "sensor time an event may arrive late", 0.0).unit("s");
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
