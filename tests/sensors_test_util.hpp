// Shared helpers of the libs/sensors tests (tests/test_sensors_*.cpp): synthetic IMU/scan/image streams with
// the point id in the intensity, their arrival order, a Recombiner harness and the structural frame checks.
#pragma once

#include "livo/sensors/preprocess_config.hpp"
#include "livo/sensors/recombiner.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <limits>
#include <map>
#include <random>
#include <tuple>
#include <vector>

namespace livo::test {

inline constexpr Utime kT0 = 1'000'000'000;  // 1000 s: stamps far from zero
inline const float kNaN = std::numeric_limits<float>::quiet_NaN();

// ------------------------------------------------------------------ synthetic streams

struct Scenario {
  double duration_s = 2.0;
  double imu_rate_hz = 200.0;
  double scan_period_s = 0.1;
  int points_per_scan = 400;
  double image_period_s = 0.1;
  double image_phase_s = 0.037;
  double frac_nan = 0.0, frac_blind = 0.0, frac_range = 0.0;
  unsigned seed = 1;
};

struct Data {
  std::vector<ImuSample> imu;
  std::vector<LidarScan> scans;
  std::vector<Image> images;
};

inline Image grayImage(Utime t) {
  Image im;
  im.utime = t;
  im.width = 8;
  im.height = 4;
  im.row_stride = 8;
  im.data.assign(32, 7);
  return im;
}

// Point id in the intensity (exact below 2^24). Some scans are shuffled (points not in time order),
// and every image time inside a scan gets a point exactly at it and one 1 µs later.
inline Data generate(const Scenario& s) {
  std::mt19937 rng(s.seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  Data d;
  const Utime end = kT0 + fromSeconds(s.duration_s);
  for (Utime t = kT0; t <= end; t += fromSeconds(1.0 / s.imu_rate_hz)) {
    ImuSample m;
    m.utime = t;
    m.gyro = Eigen::Vector3d(0.1, 0.0, 0.0);
    m.accel = Eigen::Vector3d(0.0, 0.0, 9.81);
    d.imu.push_back(m);
  }
  for (Utime t = kT0 + fromSeconds(s.image_phase_s); t <= end; t += fromSeconds(s.image_period_s))
    d.images.push_back(grayImage(t));
  int id = 0;
  for (Utime start = kT0; start + fromSeconds(s.scan_period_s) <= end; start += fromSeconds(s.scan_period_s)) {
    LidarScan scan;
    scan.utime = start;
    scan.sensor = "test";
    std::vector<float> offsets;
    for (int i = 0; i < s.points_per_scan; ++i) offsets.push_back(static_cast<float>(u(rng) * s.scan_period_s));
    for (const Image& im : d.images) {
      const Utime dt = im.utime - start;
      if (dt >= 0 && dt < fromSeconds(s.scan_period_s) - 1) {
        offsets.push_back(static_cast<float>(toSeconds(dt)));
        offsets.push_back(static_cast<float>(toSeconds(dt + 1)));
      }
    }
    std::sort(offsets.begin(), offsets.end());
    for (float off : offsets) {
      LidarPoint p;
      const Eigen::Vector3d dir = Eigen::Vector3d(u(rng) - 0.5, u(rng) - 0.5, u(rng) - 0.5).normalized();
      double range = 1.0 + 40.0 * u(rng);
      const double r = u(rng);
      if (r < s.frac_blind) range = 0.3;
      else if (r < s.frac_blind + s.frac_range) range = 150.0;
      p.p_lidar = (dir * range).cast<float>();
      if (u(rng) < s.frac_nan) p.p_lidar.y() = kNaN;
      p.time_offset_s = off;
      p.intensity = static_cast<float>(id++);
      scan.points.push_back(p);
    }
    if (scan.utime % 3 == 0) std::shuffle(scan.points.begin(), scan.points.end(), rng);
    d.scans.push_back(std::move(scan));
  }
  return d;
}

// Messages in arrival order: IMU 0.5 ms after its stamp, images 2 ms after, scans 5 ms after their end.
struct Event {
  Utime arrival;
  int kind;  // 0 IMU, 1 scan, 2 image
  std::size_t index;
};
inline std::vector<Event> arrivalOrder(const Data& d, double scan_period_s = 0.1) {
  std::vector<Event> ev;
  for (std::size_t i = 0; i < d.imu.size(); ++i) ev.push_back({d.imu[i].utime + 500, 0, i});
  for (std::size_t i = 0; i < d.scans.size(); ++i)
    ev.push_back({d.scans[i].utime + fromSeconds(scan_period_s) + 5000, 1, i});
  for (std::size_t i = 0; i < d.images.size(); ++i) ev.push_back({d.images[i].utime + 2000, 2, i});
  std::stable_sort(ev.begin(), ev.end(), [](const Event& a, const Event& b) {
    return std::tie(a.arrival, a.kind) < std::tie(b.arrival, b.kind);
  });
  return ev;
}

struct Harness {
  explicit Harness(const PreprocessConfig& cfg) : r(cfg) {}
  Recombiner r;
  std::vector<Frame> frames;
  void drain() {
    Frame f;
    while (r.nextFrame(f)) frames.push_back(f);
  }
  void feed(const Data& d, const Event& e) {
    if (e.kind == 0) r.addImu(d.imu[e.index]);
    if (e.kind == 1) r.addScan(d.scans[e.index]);
    if (e.kind == 2) r.addImage(d.images[e.index]);
    drain();
  }
  void feedAll(const Data& d) {
    for (const Event& e : arrivalOrder(d)) feed(d, e);
  }
  void finish() {
    r.flush();
    drain();
  }
};

inline PreprocessConfig testConfig(bool camera) {
  PreprocessConfig c;
  c.camera_enabled = camera;
  c.blind_m = 0.5;
  c.max_range_m = 100.0;
  return c;
}

inline std::uint64_t accountedPoints(const PreprocessStats& s, std::size_t pending) {
  return s.points_nan + s.points_bad_time + s.points_blind + s.points_range + s.points_decimated +
         s.points_out_of_order + s.points_late + s.points_overflow + s.points_voxel_merged + s.points_emitted +
         pending;
}

// Structural invariants every run must satisfy. Returns the id -> frame index map.
inline std::map<int, std::size_t> checkFrames(const Harness& h) {
  std::map<int, std::size_t> frame_of;
  std::uint64_t imu_incomplete = 0, empty = 0, with_image = 0;
  for (std::size_t k = 0; k < h.frames.size(); ++k) {
    const Frame& f = h.frames[k];
    EXPECT_EQ(f.sweep.utime, f.sweep_start_utime);
    EXPECT_LE(f.sweep_start_utime, f.utime);
    if (k > 0) {
      EXPECT_GT(f.utime, h.frames[k - 1].utime) << "frame " << k << " goes back in time";
      EXPECT_EQ(f.sweep_start_utime, h.frames[k - 1].utime) << "frame " << k;
    }
    for (std::size_t i = 0; i < f.sweep.points.size(); ++i) {
      const LidarPoint& p = f.sweep.points[i];
      EXPECT_TRUE(p.p_lidar.allFinite());
      if (i > 0) {
        EXPECT_LE(f.sweep.points[i - 1].time_offset_s, p.time_offset_s) << "unsorted sweep " << k;
      }
      const double t = static_cast<double>(f.sweep.utime) + 1e6 * static_cast<double>(p.time_offset_s);
      EXPECT_GE(t, static_cast<double>(f.sweep_start_utime) - 1.0);
      EXPECT_LE(t, static_cast<double>(f.utime) + 1.0);
      const int id = static_cast<int>(p.intensity);
      EXPECT_TRUE(frame_of.emplace(id, k).second) << "point " << id << " in two frames";
    }
    for (std::size_t i = 1; i < f.imu.size(); ++i) EXPECT_LT(f.imu[i - 1].utime, f.imu[i].utime);
    if (f.imu.empty() || f.imu.front().utime > f.sweep_start_utime || f.imu.back().utime < f.utime)
      ++imu_incomplete;
    if (f.sweep.points.empty()) ++empty;
    if (f.has_image) {
      ++with_image;
      EXPECT_EQ(f.image.utime, f.utime);
      EXPECT_EQ(f.image.format, PixelFormat::Gray8);
    }
  }
  const PreprocessStats& s = h.r.stats();
  EXPECT_EQ(s.frames, h.frames.size());
  EXPECT_EQ(s.frames_imu_incomplete, imu_incomplete);
  EXPECT_EQ(s.empty_sweeps, empty);
  EXPECT_EQ(s.images_used, with_image);
  EXPECT_EQ(s.frames_without_image, h.frames.size() - with_image);
  EXPECT_EQ(s.points_in, accountedPoints(s, h.r.pendingPoints())) << s.summary();
  EXPECT_EQ(s.images_in, s.images_used + s.imagesDropped() + h.r.pendingImages()) << s.summary();
  return frame_of;
}

/// Absolute (corrected) time of every point that passes the filters, by id.
inline std::map<int, Utime> validPointTimes(const Data& d, const PreprocessConfig& c) {
  std::map<int, Utime> t;
  for (const LidarScan& s : d.scans)
    for (const LidarPoint& p : s.points) {
      const double r = p.p_lidar.cast<double>().norm();
      if (!p.p_lidar.allFinite() || r < c.blind_m || r > c.max_range_m) continue;
      t[static_cast<int>(p.intensity)] = s.utime + fromSeconds(c.lidar_time_offset_s) + fromSeconds(p.time_offset_s);
    }
  return t;
}


}  // namespace livo::test
