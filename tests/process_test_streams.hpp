// Synthetic message streams for the process tests (tests/test_process*.cpp): raw sensor messages as a
// driver would send them, and per-frame estimator outputs. Deterministic (fixed values, no RNG state
// shared between tests).
#pragma once

#include "livo/io/convert.hpp"
#include "livo/io/estimator_messages.hpp"
#include "livo/io/map_messages.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

namespace livo::test {

struct StreamEvent {
  std::string channel;
  Utime send_utime = 0;  ///< when a driver publishes it (a scan: at its end)
  int order = 0;         ///< tie-break at equal send times: IMU, image, scan
  std::vector<std::uint8_t> bytes;
};

struct SensorStream {
  std::vector<StreamEvent> events;  ///< sorted by send time
  std::vector<Utime> image_times;
  Utime t0 = 0;
};

constexpr Utime kStreamT0 = 1'000'000'000;  // 1000 s

/// IMU at 200 Hz, LiDAR scans of `points_per_scan` points at 10 Hz (each spanning 0.1 s, published
/// at its end), RGB8 images of `width` x `height` at 10 Hz, 50 ms after each scan start; `duration_s`
/// long.
inline SensorStream makeSensorStream(double duration_s = 2.0, int points_per_scan = 200, int width = 40,
                                     int height = 30) {
  SensorStream s;
  s.t0 = kStreamT0;
  const Utime dur = Utime(std::llround(duration_s * 1e6));
  for (Utime t = s.t0; t <= s.t0 + dur; t += 5000) {
    ImuSample imu;
    imu.utime = t;
    imu.gyro = Eigen::Vector3d(0.0, 0.0, 0.1);
    imu.accel = Eigen::Vector3d(0.0, 0.0, 9.81);
    s.events.push_back({"LIVO_IMU", t, 0, encode(toMsg(imu))});
  }
  for (Utime t = s.t0; t + 100000 <= s.t0 + dur; t += 100000) {
    LidarScan scan;
    scan.utime = t;
    scan.sensor = "avia";
    for (int i = 0; i < points_per_scan; ++i) {
      LidarPoint p;
      const double a = 0.02 * i;
      p.p_lidar = Eigen::Vector3f(5.0f, float(2.0 * std::sin(a)), float(1.0 * std::cos(3 * a)));
      p.time_offset_s = float(0.1 * i / points_per_scan);
      p.intensity = float(i % 256);
      p.ring = std::int16_t(i % 6);
      scan.points.push_back(p);
    }
    s.events.push_back({"LIVO_LIDAR", t + 100000, 2, encode(toMsg(scan))});
  }
  for (Utime t = s.t0 + 50000; t + 50000 <= s.t0 + dur; t += 100000) {
    Image img;
    img.utime = t;
    img.width = width;
    img.height = height;
    img.row_stride = 3 * width;
    img.format = PixelFormat::Rgb8;
    img.data.assign(std::size_t(img.row_stride) * img.height, 0);
    for (int v = 0; v < img.height; ++v)
      for (int u = 0; u < img.width; ++u) {
        std::uint8_t* px = &img.data[std::size_t(v * img.row_stride + 3 * u)];
        px[0] = std::uint8_t((4 * u) & 0xFF);  // red ramp, green and blue 100
        px[1] = 100;
        px[2] = 100;
      }
    s.image_times.push_back(t);
    s.events.push_back({"LIVO_CAMERA", t, 1, encode(toMsg(img))});
  }
  std::stable_sort(s.events.begin(), s.events.end(), [](const StreamEvent& a, const StreamEvent& b) {
    return a.send_utime != b.send_utime ? a.send_utime < b.send_utime : a.order < b.order;
  });
  return s;
}

/// One estimator frame's outputs: odometry, registered scan, stats (and map stats every 5th frame).
struct EstimatorFrame {
  OdometryOutput odom;
  RegisteredScan scan;
  EstimatorStats stats;
  bool has_map_stats = false;
  MapStats map_stats;
};

/// `n` frames at 10 Hz: the IMU moves along x (0.1 m per frame) at z = 1 with a slow yaw and sees a
/// wall at x = 5 (y in [-1, 1], z in [0, 2]). The first frame is initializing (no pose). Points with
/// y > 0 are red (0xFF0000) in camera colour, the others unseen (-1) with intensity 100.
inline std::vector<EstimatorFrame> makeEstimatorFrames(int n) {
  std::vector<EstimatorFrame> frames;
  for (int k = 0; k < n; ++k) {
    EstimatorFrame f;
    const Utime t = kStreamT0 + 100000 * Utime(k);
    f.odom.utime = t;
    f.odom.state.utime = t;
    f.odom.state.p_world_imu = Eigen::Vector3d(0.1 * k, 0.0, 1.0);
    f.odom.state.R_world_imu = Eigen::AngleAxisd(0.01 * k, Eigen::Vector3d::UnitZ()).toRotationMatrix();
    f.odom.pose_cov = Mat6::Identity() * 1e-4;
    f.odom.status = k == 0 ? odometry_status::kInitializing : (k % 4 == 0 ? odometry_status::kVisualUpdate : 0);
    f.scan.utime = t;
    for (int i = 0; i < 21; ++i)
      for (int j = 0; j < 21; ++j) {
        const float y = -1.0f + 0.1f * float(i) + 0.013f * float(k % 3);
        const float z = 0.1f * float(j);
        f.scan.points.emplace_back(5.0f, y, z);
        f.scan.intensity.push_back(100.0f);
        f.scan.rgb.push_back(y > 0.0f ? 0xFF0000 : -1);
      }
    f.stats.utime = t;
    f.stats.frame_index = k;
    f.stats.lio_ms = 2.0f + 0.25f * float(k);
    f.stats.vio_ms = k % 4 == 0 ? 1.5f : 0.0f;
    f.stats.map_ms = 0.5f;
    f.stats.total_ms = f.stats.lio_ms + f.stats.vio_ms + f.stats.map_ms;
    f.stats.sigma_min = 0.1f + 0.01f * float(k);
    f.stats.degenerate = k == 7;
    f.stats.visual_used = k % 4 == 0;
    f.stats.n_points = 441;
    f.stats.n_planes_matched = 400 - k;
    f.stats.n_visual_points = k % 4 == 0 ? 30 : 0;
    if (k % 5 == 4) {
      f.has_map_stats = true;
      f.map_stats.utime = t;
      f.map_stats.local_voxels = 100 + k;
      f.map_stats.local_planes = 300 + k;
      f.map_stats.visual_points_local = 50 + k;
      f.map_stats.visual_points_longterm = 7 * k;
      f.map_stats.bytes = 1000000 + 1000 * k;
      f.map_stats.slides = k / 5;
    }
    frames.push_back(f);
  }
  return frames;
}

}  // namespace livo::test
