// livo-convert rosbag: options and the run (conversion summary on stdout, progress and errors on stderr).
#include "cli.hpp"

#include <iostream>

namespace livo_convert {

bool parseRosbagOption(const std::vector<std::string>& args, std::size_t& i, livo::RosbagOptions& opt) {
  const std::string& a = args[i];
  auto value = [&]() -> std::string {
    if (i + 1 >= args.size()) throw UsageError(a + ": missing value");
    return args[++i];
  };
  if (a == "--lidar-topic") {
    opt.lidar_topic = value();
  } else if (a == "--imu-topic") {
    opt.imu_topic = value();
  } else if (a == "--image-topic") {
    opt.image_topic = value();
  } else if (a == "--point-time-field") {
    opt.point_time_field = value();
  } else if (a == "--imu-accel-unit") {
    const std::string u = value();
    if (u == "auto") opt.imu_accel_unit = livo::AccelUnit::Auto;
    else if (u == "g") opt.imu_accel_unit = livo::AccelUnit::G;
    else if (u == "mps2") opt.imu_accel_unit = livo::AccelUnit::MetresPerSecond2;
    else throw UsageError("--imu-accel-unit: expected auto, g or mps2, got '" + u + "'");
  } else if (a == "--gravity") {
    opt.gravity_m_s2 = parseNumber(a, value());
    if (!(opt.gravity_m_s2 > 0)) throw UsageError("--gravity must be positive");
  } else if (a == "--mono16-bits") {
    const double b = parseNumber(a, value());
    if (b != std::floor(b) || b < 9 || b > 16) throw UsageError("--mono16-bits: expected an integer 9..16");
    opt.mono16_bits = static_cast<int>(b);
  } else if (a == "--reorder-window") {
    opt.reorder_window_s = parseNumber(a, value());
    if (opt.reorder_window_s < 0) throw UsageError("--reorder-window must be >= 0");
  } else if (a == "--max-scan-span") {
    opt.max_scan_span_s = parseNumber(a, value());
    if (!(opt.max_scan_span_s > 0)) throw UsageError("--max-scan-span must be positive");
  } else if (a == "--skip-bad") {
    opt.skip_bad_messages = true;
  } else {
    return false;
  }
  return true;
}

int runRosbag(const std::string& bag, const std::string& out, livo::RosbagOptions opt, bool quiet) {
  if (!livo::rosbagSupported()) {
    std::cerr << "livo-convert: error: this livo-convert was built without ROS bag support (librosbag-storage-dev "
                 "was not found, or LIVO_WITH_ROSBAG was OFF, when the build was configured); install it (scripts/setup does) and rebuild\n";
    return 1;
  }
  opt.progress = Progress(quiet, "messages");
  const livo::RosbagSummary s = livo::convertRosbag(bag, out, opt);
  std::cout << "livo-convert rosbag: " << s.describe();
  if (!s.error.empty()) {
    std::cerr << "livo-convert: error: " << s.error << "\n"
              << "livo-convert: " << out << " keeps the " << s.conversion.events
              << " events converted before the error\n";
    return 1;
  }
  return 0;
}

}  // namespace livo_convert
