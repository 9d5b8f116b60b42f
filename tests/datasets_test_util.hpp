// Shared helpers of the dataset converter tests (tests/test_datasets_*.cpp except the ROS bag ones): shared
// data paths, a temporary folder, text writing, the DatasetError message of a call, a log decoded by channel
// and a tiny synthetic EuRoC folder (always available, no shared data needed).
#pragma once

#include "livo/datasets/csv.hpp"
#include "livo/io/convert.hpp"
#include "livo/io/log.hpp"

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>
#include <unistd.h>

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

namespace fs = std::filesystem;

namespace livo::test {

inline const fs::path kData = fs::path(LIVO_SHARED_DATA);
inline const fs::path kEuroc = kData / "euroc_v1_01_micro";
inline const fs::path kScans = kData / "kitti_newer_college_scans";

/// A fresh temporary folder removed at the end of the test.
struct TempDir {
  fs::path path;
  TempDir() {
    static int counter = 0;
    path = fs::temp_directory_path() /
           ("livo_test_datasets_" + std::to_string(::getpid()) + "_" + std::to_string(counter++));
    fs::remove_all(path);
    fs::create_directories(path);
  }
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(path, ec);
  }
  std::string operator/(const std::string& name) const { return (path / name).string(); }
};

inline void writeText(const fs::path& p, const std::string& text) {
  fs::create_directories(p.parent_path());
  std::ofstream(p) << text;
}

/// Runs `fn` and returns the DatasetError message (empty when nothing was thrown).
template <class Fn>
inline std::string errorOf(Fn&& fn) {
  try {
    fn();
  } catch (const DatasetError& e) {
    return e.what();
  }
  return "";
}

/// All events of a log, decoded by channel.
struct DecodedLog {
  std::vector<imu_t> imu;
  std::vector<image_t> images;
  std::vector<lidar_scan_t> scans;
  std::vector<Utime> log_times;
  std::vector<std::string> channels;
  bool utime_matches_log_time = true;
};

inline DecodedLog readLog(const std::string& path) {
  DecodedLog out;
  LogReader reader(path);
  LogEvent ev;
  while (reader.next(ev)) {
    out.log_times.push_back(ev.timestamp);
    out.channels.push_back(ev.channel);
    Utime utime = 0;
    if (ev.channel == "LIVO_IMU") {
      imu_t m;
      EXPECT_TRUE(decode(ev.data.data(), ev.data.size(), m)) << ev.eventnum;
      out.imu.push_back(m);
      utime = m.utime;
    } else if (ev.channel == "LIVO_CAMERA") {
      image_t m;
      EXPECT_TRUE(decode(ev.data.data(), ev.data.size(), m)) << ev.eventnum;
      out.images.push_back(m);
      utime = m.utime;
    } else if (ev.channel == "LIVO_LIDAR") {
      lidar_scan_t m;
      EXPECT_TRUE(decode(ev.data.data(), ev.data.size(), m)) << ev.eventnum;
      out.scans.push_back(m);
      utime = m.utime;
    } else {
      ADD_FAILURE() << "unexpected channel " << ev.channel;
    }
    if (utime != ev.timestamp) out.utime_matches_log_time = false;
  }
  return out;
}

// ---- a tiny synthetic EuRoC folder (always available, no shared data needed) ----
inline const char* kCamYaml = R"(%YAML:1.0
sensor_type: camera
T_BS:
  cols: 4
  rows: 4
  data: [0.0, -1.0, 0.0, 0.1,
         1.0, 0.0, 0.0, 0.2,
         0.0, 0.0, 1.0, 0.3,
         0.0, 0.0, 0.0, 1.0]
rate_hz: 20
resolution: [8, 6]
camera_model: pinhole
intrinsics: [100.0, 101.0, 4.0, 3.0] #fu, fv, cu, cv
distortion_model: radial-tangential
distortion_coefficients: [-0.1, 0.01, 0.001, 0.0001]
)";
inline const char* kImuYaml = R"(%YAML:1.0
sensor_type: imu
T_BS:
  cols: 4
  rows: 4
  data: [1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0]
rate_hz: 200
gyroscope_noise_density: 1.6968e-04
gyroscope_random_walk: 1.9393e-05
accelerometer_noise_density: 2.0000e-3
accelerometer_random_walk: 3.0000e-3
)";

/// 3 images at 1.0, 1.05, 1.1 s and IMU at 200 Hz from 0 to 3 s after an EuRoC-like epoch (ns).
inline constexpr std::int64_t kEpochNs = 1'403'715'000'000'000'000;
struct SyntheticEuroc {
  TempDir dir;
  std::string imu_csv, cam_csv;
  SyntheticEuroc() {
    const fs::path mav = dir.path / "mav0";
    writeText(mav / "cam0" / "sensor.yaml", kCamYaml);
    writeText(mav / "imu0" / "sensor.yaml", kImuYaml);
    std::ostringstream cam;
    cam << "#timestamp [ns],filename\r\n";  // EuRoC files may have CRLF endings
    for (int i = 0; i < 3; ++i) {
      const std::int64_t ns = kEpochNs + 1'000'000'000 + std::int64_t{i} * 50'000'000;
      cam << ns << "," << ns << ".png\r\n";
      cv::Mat img(6, 8, CV_8UC1);
      for (int r = 0; r < 6; ++r)
        for (int c = 0; c < 8; ++c) img.at<std::uint8_t>(r, c) = static_cast<std::uint8_t>(10 * i + 8 * r + c);
      fs::create_directories(mav / "cam0" / "data");
      cv::imwrite((mav / "cam0" / "data" / (std::to_string(ns) + ".png")).string(), img);
    }
    cam_csv = cam.str();
    std::ostringstream imu;
    imu << "#timestamp [ns],w_RS_S_x [rad s^-1],w_RS_S_y,w_RS_S_z,a_RS_S_x [m s^-2],a_RS_S_y,a_RS_S_z\n";
    for (std::int64_t i = 0; i <= 600; ++i)
      imu << kEpochNs + i * 5'000'000 << "," << 0.001 * i << ",-0.5,0.25," << 9.81 << ",0.1," << -0.01 * i << "\n";
    imu_csv = imu.str();
    writeAll();
  }
  void writeAll() const {
    writeText(dir.path / "mav0" / "cam0" / "data.csv", cam_csv);
    writeText(dir.path / "mav0" / "imu0" / "data.csv", imu_csv);
  }
  /// Replaces line `line` (1-based) of the IMU csv.
  void setImuLine(int line, const std::string& text) {
    std::istringstream in(imu_csv);
    std::ostringstream out;
    std::string l;
    for (int n = 1; std::getline(in, l); ++n) out << (n == line ? text : l) << "\n";
    imu_csv = out.str();
    writeAll();
  }
};

inline bool contains(const std::string& s, const std::string& part) { return s.find(part) != std::string::npos; }

}  // namespace livo::test
