// libs/sensors: point filtering against brute-force counts, scan recombination on synthetic streams
// (every point in exactly one frame at the right place, IMU coverage, every fault counted, no stall),
// voxel downsampling against a brute-force grouping, and real Newer College scans.
#include "livo/common/config.hpp"
#include "livo/common/timing.hpp"
#include "livo/sensors/downsample.hpp"
#include "livo/sensors/preprocess_config.hpp"
#include "livo/sensors/preprocess_points.hpp"
#include "livo/sensors/recombiner.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <iostream>
#include <limits>
#include <map>
#include <random>
#include <tuple>

using namespace livo;

namespace {

constexpr Utime kT0 = 1'000'000'000;  // 1000 s: stamps far from zero
const float kNaN = std::numeric_limits<float>::quiet_NaN();

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

Image grayImage(Utime t) {
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
Data generate(const Scenario& s) {
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
std::vector<Event> arrivalOrder(const Data& d, double scan_period_s = 0.1) {
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

PreprocessConfig testConfig(bool camera) {
  PreprocessConfig c;
  c.camera_enabled = camera;
  c.blind_m = 0.5;
  c.max_range_m = 100.0;
  return c;
}

std::uint64_t accountedPoints(const PreprocessStats& s, std::size_t pending) {
  return s.points_nan + s.points_bad_time + s.points_blind + s.points_range + s.points_decimated +
         s.points_out_of_order + s.points_late + s.points_overflow + s.points_voxel_merged + s.points_emitted +
         pending;
}

// Structural invariants every run must satisfy. Returns the id -> frame index map.
std::map<int, std::size_t> checkFrames(const Harness& h) {
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
std::map<int, Utime> validPointTimes(const Data& d, const PreprocessConfig& c) {
  std::map<int, Utime> t;
  for (const LidarScan& s : d.scans)
    for (const LidarPoint& p : s.points) {
      const double r = p.p_lidar.cast<double>().norm();
      if (!p.p_lidar.allFinite() || r < c.blind_m || r > c.max_range_m) continue;
      t[static_cast<int>(p.intensity)] = s.utime + fromSeconds(c.lidar_time_offset_s) + fromSeconds(p.time_offset_s);
    }
  return t;
}

}  // namespace

// ------------------------------------------------------------------ config

TEST(PreprocessConfig, LoadsRigSectionsAndLeavesOtherKeys) {
  const auto file = ConfigFile::parse(R"(
lidar: {model: avia, time_offset_s: -0.1, blind_m: 0.6, max_range_m: 80, point_filter_num: 3, T_imu_lidar: [0,0,0,0,0,0,1]}
imu: {rate_hz: 400, time_offset_s: 0.002, gyro_noise: 1e-3}
camera: {fx: 400, time_offset_s: 0.1}
preprocess: {min_frame_interval_s: 0.03, image_decimation: 4, max_imu_gap_s: 0.02, wait_timeout_s: 0.4,
             image_wait_timeout_s: -1, max_buffer_s: 3, max_point_offset_s: 0.5, voxel_leaf_m: 0.2}
)",
                                      "rig.yaml");
  PreprocessConfig c;
  c.load(file.root());
  EXPECT_DOUBLE_EQ(c.lidar_time_offset_s, -0.1);
  EXPECT_DOUBLE_EQ(c.blind_m, 0.6);
  EXPECT_DOUBLE_EQ(c.max_range_m, 80.0);
  EXPECT_EQ(c.point_filter_num, 3);
  EXPECT_DOUBLE_EQ(c.imu_rate_hz, 400.0);
  EXPECT_DOUBLE_EQ(c.imu_time_offset_s, 0.002);
  EXPECT_TRUE(c.camera_enabled);  // a camera section without `enabled` means enabled
  EXPECT_DOUBLE_EQ(c.camera_time_offset_s, 0.1);
  EXPECT_DOUBLE_EQ(c.min_frame_interval_s, 0.03);
  EXPECT_EQ(c.image_decimation, 4);
  EXPECT_DOUBLE_EQ(c.imuGapThresholdS(), 0.02);
  EXPECT_DOUBLE_EQ(c.wait_timeout_s, 0.4);
  EXPECT_LT(c.image_wait_timeout_s, 0.0);
  EXPECT_DOUBLE_EQ(c.max_buffer_s, 3.0);
  EXPECT_DOUBLE_EQ(c.max_point_offset_s, 0.5);
  EXPECT_DOUBLE_EQ(c.voxel_leaf_m, 0.2);
  // Keys of other modules stay unread (they are someone else's), ours are all read.
  auto unused = file.unusedKeys();
  std::sort(unused.begin(), unused.end());
  EXPECT_EQ(unused, (std::vector<std::string>{"camera.fx", "imu.gyro_noise", "lidar.T_imu_lidar", "lidar.model"}));
}

TEST(PreprocessConfig, CameraAbsentOrDisabledMeansLidarOnly) {
  PreprocessConfig a;
  a.load(ConfigFile::parse("lidar: {blind_m: 1.0}").root());
  EXPECT_FALSE(a.camera_enabled);
  EXPECT_DOUBLE_EQ(a.imuGapThresholdS(), 5.0 / 200.0);
  PreprocessConfig b;
  b.load(ConfigFile::parse("camera: {enabled: false}").root());
  EXPECT_FALSE(b.camera_enabled);
}

TEST(PreprocessConfig, BadValuesNameFileAndKey) {
  auto message = [](const std::string& yaml) {
    try {
      PreprocessConfig c;
      c.load(ConfigFile::parse(yaml, "rig.yaml").root());
    } catch (const ConfigError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(message("lidar: {blind_m: -1}").find("rig.yaml: lidar.blind_m"), std::string::npos);
  EXPECT_NE(message("lidar: {blind_m: 5, max_range_m: 2}").find("lidar.max_range_m"), std::string::npos);
  EXPECT_NE(message("lidar: {point_filter_num: 0}").find("lidar.point_filter_num"), std::string::npos);
  EXPECT_NE(message("imu: {rate_hz: 0}").find("imu.rate_hz"), std::string::npos);
  EXPECT_NE(message("preprocess: {image_decimation: 0}").find("preprocess.image_decimation"), std::string::npos);
  EXPECT_NE(message("preprocess: {wait_timeout_s: 0}").find("preprocess.wait_timeout_s"), std::string::npos);
  EXPECT_NE(message("preprocess: {max_buffer_s: 0.2}").find("preprocess.max_buffer_s"), std::string::npos);
  EXPECT_NE(message("preprocess: {wait_timeout_s: abc}").find("expected a number"), std::string::npos);
  PreprocessConfig bad;
  bad.point_filter_num = 0;
  EXPECT_THROW({ Recombiner r(bad); }, std::invalid_argument);
}

// ------------------------------------------------------------------ point filter

TEST(PointFilter, CountsEveryReasonLikeBruteForce) {
  Scenario s;
  s.points_per_scan = 5000;
  s.frac_nan = 0.05;
  s.frac_blind = 0.1;
  s.frac_range = 0.1;
  const Data d = generate(s);
  LidarScan scan = d.scans[3];
  scan.points[10].time_offset_s = 5.f;   // bad time
  scan.points[11].time_offset_s = kNaN;  // non-finite time
  PreprocessConfig c = testConfig(false);
  c.point_filter_num = 3;
  // Brute force: the same order of tests written out per point.
  std::uint64_t nan = 0, bad = 0, blind = 0, range = 0, decimated = 0, passed = 0;
  std::vector<int> kept_ids;
  for (const LidarPoint& p : scan.points) {
    const double r = p.p_lidar.cast<double>().norm();
    if (!p.p_lidar.allFinite() || !std::isfinite(p.time_offset_s)) ++nan;
    else if (std::abs(p.time_offset_s) > c.max_point_offset_s) ++bad;
    else if (r < c.blind_m) ++blind;
    else if (r > c.max_range_m) ++range;
    else if (passed++ % 3 != 0) ++decimated;
    else kept_ids.push_back(static_cast<int>(p.intensity));
  }
  PreprocessStats st;
  std::vector<StampedPoint> out;
  const Utime start = kT0 + 123;
  filterScanPoints(scan, start, c, st, out);
  EXPECT_EQ(st.points_in, scan.points.size());
  EXPECT_EQ(st.points_nan, nan);
  EXPECT_EQ(st.points_bad_time, bad);
  EXPECT_EQ(st.points_blind, blind);
  EXPECT_EQ(st.points_range, range);
  EXPECT_EQ(st.points_decimated, decimated);
  ASSERT_EQ(out.size(), kept_ids.size());
  EXPECT_GT(nan, 200u);
  EXPECT_GT(blind, 400u);
  EXPECT_GT(range, 400u);
  for (std::size_t i = 0; i < out.size(); ++i) {
    EXPECT_EQ(static_cast<int>(out[i].point.intensity), kept_ids[i]);
    EXPECT_EQ(out[i].utime, start + fromSeconds(out[i].point.time_offset_s));
  }
}

// ------------------------------------------------------------------ recombination, clean streams

TEST(Recombiner, CameraModeRecutsAtImageTimesWithOffsets) {
  Scenario s;
  s.frac_nan = 0.02;
  s.frac_blind = 0.05;
  s.frac_range = 0.05;
  const Data d = generate(s);
  PreprocessConfig c = testConfig(true);
  c.lidar_time_offset_s = 0.0105;
  c.imu_time_offset_s = -0.0021;
  c.camera_time_offset_s = -0.0032;
  Harness h(c);
  h.feedAll(d);
  const std::size_t before_flush = h.frames.size();
  h.finish();
  const auto frame_of = checkFrames(h);
  const PreprocessStats& st = h.r.stats();

  // Frame times: every image after the first LiDAR point, on the corrected clock.
  const auto valid = validPointTimes(d, c);
  Utime first_point = valid.begin()->second;
  for (const auto& kv : valid) first_point = std::min(first_point, kv.second);
  std::vector<Utime> expected_ends;
  for (const Image& im : d.images) {
    const Utime t = im.utime + fromSeconds(c.camera_time_offset_s);
    if (t > first_point) expected_ends.push_back(t);
  }
  ASSERT_EQ(before_flush, expected_ends.size()) << "every image frame is ready before the end of input";
  for (std::size_t k = 0; k < before_flush; ++k) {
    EXPECT_EQ(h.frames[k].utime, expected_ends[k]);
    EXPECT_TRUE(h.frames[k].has_image);
  }
  // flush(): the points after the last image become one last frame without image at the scan end.
  ASSERT_EQ(h.frames.size(), before_flush + 1);
  EXPECT_FALSE(h.frames.back().has_image);
  Utime last_point = 0;
  for (const auto& kv : valid) last_point = std::max(last_point, kv.second);
  EXPECT_EQ(h.frames.back().utime, last_point);
  expected_ends.push_back(last_point);
  EXPECT_EQ(h.frames.front().sweep_start_utime, first_point);
  EXPECT_EQ(st.images_no_lidar, d.images.size() - before_flush);
  EXPECT_EQ(st.frames_imu_incomplete, 1u) << "only the flushed frame, past the end of the IMU";
  EXPECT_LT(h.frames.back().imu.back().utime, h.frames.back().utime);
  EXPECT_EQ(st.frames_lidar_incomplete, 0u);
  EXPECT_EQ(st.points_late + st.points_overflow + st.empty_sweeps, 0u);

  // Oracle: a valid point belongs to the first frame ending at or after its time; later ones pend.
  std::size_t pending = 0;
  for (const auto& kv : valid) {
    const auto it = std::lower_bound(expected_ends.begin(), expected_ends.end(), kv.second);
    if (it == expected_ends.end()) {
      ++pending;
      EXPECT_EQ(frame_of.count(kv.first), 0u);
      continue;
    }
    const auto f = frame_of.find(kv.first);
    ASSERT_NE(f, frame_of.end()) << "point " << kv.first << " lost";
    EXPECT_EQ(f->second, static_cast<std::size_t>(it - expected_ends.begin())) << "point " << kv.first;
  }
  EXPECT_EQ(pending, h.r.pendingPoints());
  EXPECT_EQ(frame_of.size() + pending, valid.size());
  // Boundary points: exactly at t_c in that frame, 1 µs later in the next (checked above by the oracle);
  // the reconstructed times are exact to the microsecond here (sweeps < 0.2 s).
  for (const Frame& f : h.frames)
    for (const LidarPoint& p : f.sweep.points)
      EXPECT_EQ(f.sweep.utime + fromSeconds(p.time_offset_s), valid.at(static_cast<int>(p.intensity)));

  // IMU: corrected stamps, contiguous, bracketing each sweep with one sample on each side.
  std::vector<Utime> imu_times;
  for (const ImuSample& m : d.imu) imu_times.push_back(m.utime - fromSeconds(c.imu_time_offset_s));
  for (std::size_t k = 0; k < before_flush; ++k) {
    const Frame& f = h.frames[k];
    ASSERT_GE(f.imu.size(), 2u);
    const auto lo = std::lower_bound(imu_times.begin(), imu_times.end(), f.imu.front().utime);
    const auto hi = std::upper_bound(imu_times.begin(), imu_times.end(), f.imu.back().utime);
    EXPECT_EQ(static_cast<std::size_t>(hi - lo), f.imu.size());
    EXPECT_LE(f.imu.front().utime, f.sweep_start_utime);
    EXPECT_GT(f.imu[1].utime, f.sweep_start_utime);
    EXPECT_GE(f.imu.back().utime, f.utime);
    EXPECT_LT(f.imu[f.imu.size() - 2].utime, f.utime);
  }
}

TEST(Recombiner, LidarOnlyFramesAtScanEnds) {
  Scenario s;
  s.frac_blind = 0.05;
  const Data d = generate(s);
  PreprocessConfig c = testConfig(false);
  Harness h(c);
  h.feedAll(d);
  h.finish();
  const auto frame_of = checkFrames(h);
  const PreprocessStats& st = h.r.stats();
  ASSERT_EQ(h.frames.size(), d.scans.size());
  EXPECT_EQ(st.images_ignored, d.images.size());
  EXPECT_EQ(h.r.pendingPoints(), 0u);
  const auto valid = validPointTimes(d, c);
  for (std::size_t k = 0; k < d.scans.size(); ++k) {
    Utime last = 0;
    std::size_t n = 0;
    for (const LidarPoint& p : d.scans[k].points) {
      const auto it = valid.find(static_cast<int>(p.intensity));
      if (it == valid.end()) continue;
      last = std::max(last, it->second);
      ++n;
      EXPECT_EQ(frame_of.at(it->first), k);
    }
    EXPECT_EQ(h.frames[k].utime, last) << "frame " << k << " must end at the scan's last point";
    EXPECT_EQ(h.frames[k].sweep.points.size(), n);
    EXPECT_FALSE(h.frames[k].has_image);
  }
  EXPECT_EQ(st.frames_imu_incomplete, 0u);
}

// ------------------------------------------------------------------ faults

TEST(Recombiner, ImuOutOfOrderDuplicatesAndInvalidAreDropped) {
  Data d = generate(Scenario{});
  std::swap(d.imu[50], d.imu[51]);  // 51 arrives first, then 50 is out of order
  d.imu.insert(d.imu.begin() + 100, d.imu[100]);
  d.imu.insert(d.imu.begin() + 200, d.imu[200]);
  d.imu[300].accel.x() = std::numeric_limits<double>::infinity();
  // IMU messages arrive in vector order (about one per 5 ms), the faulty stamps included.
  auto events = arrivalOrder(d);
  for (Event& e : events)
    if (e.kind == 0) e.arrival = kT0 + static_cast<Utime>(e.index) * 5000 + 500;
  std::stable_sort(events.begin(), events.end(), [](const Event& a, const Event& b) { return a.arrival < b.arrival; });
  Harness h(testConfig(true));
  for (const Event& e : events) h.feed(d, e);
  h.finish();
  checkFrames(h);
  const PreprocessStats& st = h.r.stats();
  EXPECT_EQ(st.frames_lidar_incomplete, 0u);
  EXPECT_EQ(st.images_used, d.images.size());
  EXPECT_EQ(st.imu_out_of_order, 1u);
  EXPECT_EQ(st.imu_duplicates, 2u);
  EXPECT_EQ(st.imu_invalid, 1u);
  EXPECT_EQ(st.imu_in, d.imu.size());
  EXPECT_EQ(st.frames_imu_incomplete, 0u);
}

TEST(Recombiner, BackwardJumpsDropTheOffendingScanAndImage) {
  Data d = generate(Scenario{});
  LidarScan old_scan = d.scans[2];
  Image old_image = d.images[3];
  Harness h(testConfig(true));
  const auto events = arrivalOrder(d);
  std::size_t replayed_points = 0;
  for (std::size_t i = 0; i < events.size(); ++i) {
    h.feed(d, events[i]);
    if (events[i].kind == 1 && events[i].index == 8) {  // the clock jumps back after scan 8
      h.r.addScan(old_scan);
      h.r.addImage(old_image);
      Image repeat = d.images[9];
      h.r.addImage(repeat);  // same stamp as an image already buffered or used
      replayed_points = old_scan.points.size();
      h.drain();
    }
  }
  h.finish();
  checkFrames(h);
  const PreprocessStats& st = h.r.stats();
  EXPECT_EQ(st.scans_out_of_order, 1u);
  EXPECT_EQ(st.points_out_of_order, replayed_points);
  EXPECT_EQ(st.images_stale + st.images_out_of_order, 2u);
  EXPECT_EQ(st.images_stale, 1u) << "image 3 precedes frames already emitted";
}

TEST(Recombiner, NanPointsAndEmptyScansAreCounted) {
  Data d = generate(Scenario{});
  for (LidarPoint& p : d.scans[4].points) p.p_lidar.x() = kNaN;  // a scan of NaN only
  d.scans[7].points.clear();                                     // an empty scan
  for (PreprocessConfig c : {testConfig(false), testConfig(true)}) {
    Harness h(c);
    h.feedAll(d);
    h.finish();
    checkFrames(h);
    const PreprocessStats& st = h.r.stats();
    EXPECT_EQ(st.scans_empty, 2u);
    EXPECT_EQ(st.points_nan, d.scans[4].points.size());
    if (!c.camera_enabled) {
      EXPECT_EQ(h.frames.size(), d.scans.size() - 2);
    }
    for (const Frame& f : h.frames)
      for (const LidarPoint& p : f.sweep.points) EXPECT_TRUE(p.p_lidar.allFinite());
  }
}

TEST(Recombiner, ImuGapIsCountedAndFramesStillBracketed) {
  Data d = generate(Scenario{});
  const Utime gap_start = kT0 + fromSeconds(0.8);
  const Utime gap_end = gap_start + fromSeconds(0.5);
  d.imu.erase(std::remove_if(d.imu.begin(), d.imu.end(),
                             [&](const ImuSample& m) { return m.utime > gap_start && m.utime < gap_end; }),
              d.imu.end());
  Harness h(testConfig(true));
  h.feedAll(d);
  h.finish();
  checkFrames(h);
  const PreprocessStats& st = h.r.stats();
  EXPECT_EQ(st.imu_gaps, 1u);
  EXPECT_NEAR(st.imu_max_gap_s, 0.5, 1e-6);
  EXPECT_EQ(st.frames_imu_incomplete, 0u) << "the samples on both sides of the gap bracket those frames";
  EXPECT_EQ(st.frames_lidar_incomplete, 0u);
  int gap_frames = 0;
  for (const Frame& f : h.frames) {
    if (f.utime > gap_start && f.utime < gap_end) {
      ++gap_frames;
      EXPECT_EQ(f.imu.back().utime, gap_end);
    }
    if (f.sweep_start_utime > gap_start && f.sweep_start_utime < gap_end) {
      EXPECT_EQ(f.imu.front().utime, gap_start);
    }
  }
  EXPECT_EQ(gap_frames, 5);
}

TEST(Recombiner, ImageGuards) {
  Data d = generate(Scenario{});
  Image close = grayImage(d.images[5].utime + fromSeconds(0.01));  // 10 ms after a kept image
  Image rgb = grayImage(d.images[6].utime + fromSeconds(0.05));
  rgb.format = PixelFormat::Rgb8;
  Image truncated = grayImage(d.images[6].utime + fromSeconds(0.06));
  truncated.data.resize(10);
  d.images.push_back(close);
  d.images.push_back(rgb);
  d.images.push_back(truncated);
  std::sort(d.images.begin(), d.images.end(), [](const Image& a, const Image& b) { return a.utime < b.utime; });
  Harness h(testConfig(true));
  h.feedAll(d);
  Image before_last = grayImage(h.frames.back().utime - fromSeconds(0.05));
  h.r.addImage(before_last);  // before the last frame
  h.finish();
  checkFrames(h);
  const PreprocessStats& st = h.r.stats();
  EXPECT_EQ(st.images_too_close, 1u);
  EXPECT_EQ(st.images_invalid, 2u);
  EXPECT_EQ(st.images_stale, 1u);
  for (const Frame& f : h.frames) EXPECT_NE(f.utime, close.utime);

  // Hilti: 40 Hz images, keep 1 in 4.
  Scenario s40;
  s40.image_period_s = 0.025;
  s40.image_phase_s = 0.01;
  const Data d40 = generate(s40);
  PreprocessConfig c = testConfig(true);
  c.image_decimation = 4;
  Harness h40(c);
  h40.feedAll(d40);
  h40.finish();
  checkFrames(h40);
  EXPECT_EQ(h40.r.stats().images_decimated, d40.images.size() - (d40.images.size() + 3) / 4);
  for (std::size_t k = 1; k < h40.frames.size(); ++k)
    if (h40.frames[k].has_image) {
      EXPECT_EQ(h40.frames[k].utime - h40.frames[k - 1].utime, fromSeconds(0.1));
    }
}

TEST(Recombiner, LidarStopNeverBlocks) {
  Data d = generate(Scenario{});
  d.scans.resize(8);  // LiDAR stops after 0.8 s, IMU and images go on to 2 s
  PreprocessConfig c = testConfig(true);
  Harness h(c);
  const auto events = arrivalOrder(d);
  Utime last_arrival = 0;
  for (const Event& e : events) {
    h.feed(d, e);
    last_arrival = e.arrival;
    // Images older than the timeout have been turned into frames: no unbounded wait.
    EXPECT_LE(h.r.pendingImages(), static_cast<std::size_t>(c.wait_timeout_s / 0.1) + 2);
  }
  const std::size_t before_flush = h.frames.size();
  h.finish();
  checkFrames(h);
  const PreprocessStats& st = h.r.stats();
  EXPECT_EQ(before_flush, 15u);  // images up to 1.437 s: 0.5 s before the last data
  EXPECT_GE(h.frames.back().utime, last_arrival - fromSeconds(0.2));
  EXPECT_GE(st.empty_sweeps, 9u);
  EXPECT_GE(st.frames_lidar_incomplete, 10u);
  EXPECT_EQ(h.r.pendingImages(), 0u);
}

TEST(Recombiner, CameraStopFallsBackToScanEndFrames) {
  Data d = generate(Scenario{});
  const Utime stop = kT0 + fromSeconds(0.9);
  d.images.erase(std::remove_if(d.images.begin(), d.images.end(), [&](const Image& im) { return im.utime > stop; }),
                 d.images.end());
  Harness h(testConfig(true));
  h.feedAll(d);
  const std::size_t frames_before_flush = h.frames.size();
  h.finish();
  checkFrames(h);
  const PreprocessStats& st = h.r.stats();
  EXPECT_GT(st.frames_without_image, 5u);
  EXPECT_GT(frames_before_flush, d.images.size() + 5) << "scan-end frames flow while the data goes on";
  EXPECT_EQ(h.r.pendingPoints(), 0u) << "after flush every scan end is a frame";
  for (const Frame& f : h.frames)
    if (!f.has_image) {
      EXPECT_GT(f.utime, d.images.back().utime);
      EXPECT_LT(f.imu.front().utime, f.utime);
    }
}

TEST(Recombiner, ImuStopNeverBlocks) {
  Data d = generate(Scenario{});
  d.imu.resize(d.imu.size() / 2);  // IMU stops at 1 s
  Harness h(testConfig(true));
  h.feedAll(d);
  const std::size_t before_flush = h.frames.size();
  h.finish();
  checkFrames(h);
  EXPECT_GE(before_flush, d.images.size() - 6);  // all but the last timeout's worth
  EXPECT_GE(h.r.stats().frames_imu_incomplete, 8u);
}

TEST(Recombiner, BuffersStayBoundedWithoutImages) {
  Scenario s;
  s.duration_s = 12.0;
  s.points_per_scan = 100;
  Data d = generate(s);
  d.images.clear();
  PreprocessConfig c = testConfig(true);
  c.image_wait_timeout_s = 0.0;  // pure image framing: the points wait for images that never come
  c.max_buffer_s = 2.0;
  Harness h(c);
  for (const Event& e : arrivalOrder(d)) {
    h.feed(d, e);
    EXPECT_LE(h.r.bufferedImu(), 2u * 200u + 2u);
    EXPECT_LE(h.r.pendingPoints(), 2u * 10u * 104u + 104u);
  }
  h.finish();
  checkFrames(h);
  EXPECT_EQ(h.frames.size(), 0u);
  EXPECT_GT(h.r.stats().points_overflow, 800u);
}

TEST(Recombiner, ForwardGlitchesAreDroppedAndRealJumpsKept) {
  const Data clean = generate(Scenario{});
  Harness ref(testConfig(true));
  ref.feedAll(clean);
  ref.finish();

  // One far-future stamp per stream, among otherwise clean data: the frames must not change.
  Data d = clean;
  ImuSample bad_imu = d.imu[100];
  bad_imu.utime += fromSeconds(100.0);
  LidarScan bad_scan = d.scans[5];
  bad_scan.utime += fromSeconds(100.0);
  Image bad_image = d.images[7];
  bad_image.utime += fromSeconds(100.0);
  Harness h(testConfig(true));
  for (const Event& e : arrivalOrder(d)) {
    h.feed(d, e);
    if (e.kind == 0 && e.index == 100) h.r.addImu(bad_imu);
    if (e.kind == 1 && e.index == 5) h.r.addScan(bad_scan);
    if (e.kind == 2 && e.index == 7) h.r.addImage(bad_image);
    h.drain();
  }
  h.finish();
  checkFrames(h);
  const PreprocessStats& st = h.r.stats();
  EXPECT_EQ(st.imu_glitches, 1u);
  EXPECT_EQ(st.scans_glitches, 1u);
  EXPECT_EQ(st.images_glitches, 1u);
  EXPECT_EQ(st.points_out_of_order, bad_scan.points.size());
  EXPECT_EQ(st.forward_jumps, 0u);
  ASSERT_EQ(h.frames.size(), ref.frames.size());
  for (std::size_t k = 0; k < h.frames.size(); ++k) {
    EXPECT_EQ(h.frames[k].utime, ref.frames[k].utime);
    EXPECT_EQ(h.frames[k].sweep.points.size(), ref.frames[k].sweep.points.size());
    EXPECT_EQ(h.frames[k].imu.size(), ref.frames[k].imu.size());
  }

  // A real 3 s pause of the whole rig: every stream resumes later and nothing is lost.
  Data p = clean;
  const Utime pause_at = kT0 + fromSeconds(1.0), pause = fromSeconds(3.0);
  for (ImuSample& m : p.imu) m.utime += m.utime > pause_at ? pause : 0;
  for (LidarScan& sc : p.scans) sc.utime += sc.utime >= pause_at ? pause : 0;
  for (Image& im : p.images) im.utime += im.utime > pause_at ? pause : 0;
  Harness hp(testConfig(true));
  hp.feedAll(p);
  hp.finish();
  checkFrames(hp);
  const PreprocessStats& sp = hp.r.stats();
  EXPECT_EQ(sp.forward_jumps, 3u);
  EXPECT_EQ(sp.imu_glitches + sp.scans_glitches + sp.images_glitches, 0u);
  EXPECT_EQ(sp.images_used, ref.r.stats().images_used);
  EXPECT_EQ(sp.points_late + sp.points_overflow + sp.points_out_of_order, 0u);
  EXPECT_EQ(sp.points_emitted, ref.r.stats().points_emitted);
  EXPECT_LE(sp.frames_without_image, ref.r.stats().frames_without_image + 1) << "one frame ends the pre-pause sweep";
}

TEST(Recombiner, SingleScanAndImageGiveFramesAfterFlush) {
  const Data d = generate(Scenario{});
  for (bool camera : {false, true}) {
    Harness h(testConfig(camera));
    h.r.addImu(d.imu[0]);
    h.r.addScan(d.scans[0]);
    h.r.addImage(d.images[0]);
    h.drain();
    EXPECT_TRUE(h.frames.empty()) << "the first item of each stream waits for confirmation";
    h.finish();
    checkFrames(h);
    ASSERT_GE(h.frames.size(), 1u);
    EXPECT_EQ(h.frames[0].has_image, camera);
    EXPECT_EQ(h.frames[0].utime, camera ? d.images[0].utime : d.scans[0].endUtime());
  }
}

TEST(Recombiner, RandomFaultsKeepInvariants) {
  for (unsigned seed = 1; seed <= 6; ++seed) {
    Scenario s;
    s.seed = seed;
    s.duration_s = 3.0;
    s.frac_nan = 0.01;
    Data d = generate(s);
    std::mt19937 rng(seed * 77);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    auto events = arrivalOrder(d);  // messages arrive at their true times, whatever their stamps say
    for (std::size_t i = 0; i + 1 < events.size(); ++i)  // and some overtake others
      if (u(rng) < 0.05) std::swap(events[i], events[i + 1]);
    auto glitch = [&](Utime& t) {
      if (u(rng) < 0.01) t += fromSeconds(50.0 + 10.0 * u(rng));  // far-future stamp
    };
    for (ImuSample& m : d.imu) {
      if (u(rng) < 0.03) m.utime -= fromSeconds(u(rng) * 0.02);  // jitter backwards
      glitch(m.utime);
    }
    for (LidarScan& sc : d.scans) {
      if (u(rng) < 0.1) sc.points.clear();
      if (u(rng) < 0.1) sc.utime -= fromSeconds(0.15);  // overlaps / jumps back past the previous scan
      glitch(sc.utime);
    }
    for (Image& im : d.images) {
      if (u(rng) < 0.1) im.utime -= fromSeconds(u(rng) * 0.2);
      glitch(im.utime);
    }
    const bool camera = seed % 2 == 0;
    PreprocessConfig c = testConfig(camera);
    c.point_filter_num = 1 + static_cast<int>(seed % 3);
    Harness h(c);
    for (const Event& e : events) h.feed(d, e);
    h.finish();
    SCOPED_TRACE("seed " + std::to_string(seed));
    checkFrames(h);
    EXPECT_GT(h.frames.size(), 10u);
    EXPECT_GT(h.r.stats().imu_glitches, 0u);
    EXPECT_EQ(h.r.stats().forward_jumps, 0u);
    EXPECT_LT(h.frames.back().utime, kT0 + fromSeconds(10.0));
  }
}

TEST(Recombiner, SweepVoxelFilterIsAccounted) {
  Scenario s;
  s.points_per_scan = 3000;
  const Data d = generate(s);
  PreprocessConfig c = testConfig(true);
  c.voxel_leaf_m = 4.0;
  Harness h(c);
  h.feedAll(d);
  h.finish();
  const PreprocessStats& st = h.r.stats();
  EXPECT_GT(st.points_voxel_merged, 1000u);
  EXPECT_EQ(st.points_in, accountedPoints(st, h.r.pendingPoints()));
  for (const Frame& f : h.frames)
    for (std::size_t i = 1; i < f.sweep.points.size(); ++i)
      EXPECT_LE(f.sweep.points[i - 1].time_offset_s, f.sweep.points[i].time_offset_s);
}

// ------------------------------------------------------------------ voxel downsampling

namespace {

struct BruteVoxel {
  std::size_t first;
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  double t = 0.0;
  int n = 0;
};

std::vector<BruteVoxel> bruteGroups(const std::vector<LidarPoint>& pts, double leaf) {
  std::map<std::tuple<long, long, long>, BruteVoxel> groups;
  for (std::size_t i = 0; i < pts.size(); ++i) {
    const Eigen::Vector3d p = pts[i].p_lidar.cast<double>();
    if (!p.allFinite()) continue;
    const auto key = std::make_tuple(static_cast<long>(std::floor(p.x() / leaf)),
                                     static_cast<long>(std::floor(p.y() / leaf)),
                                     static_cast<long>(std::floor(p.z() / leaf)));
    auto it = groups.find(key);
    if (it == groups.end()) it = groups.emplace(key, BruteVoxel{i}).first;
    it->second.sum += p;
    it->second.t += pts[i].time_offset_s;
    ++it->second.n;
  }
  std::vector<BruteVoxel> out;
  for (const auto& kv : groups) out.push_back(kv.second);
  std::sort(out.begin(), out.end(), [](const BruteVoxel& a, const BruteVoxel& b) { return a.first < b.first; });
  return out;
}

}  // namespace

TEST(VoxelDownsample, MatchesBruteForceGrouping) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-20.0, 20.0);
  std::vector<LidarPoint> pts;
  for (int i = 0; i < 20000; ++i) {
    LidarPoint p;
    p.p_lidar = Eigen::Vector3f(static_cast<float>(u(rng)), static_cast<float>(u(rng) * 0.1),
                                static_cast<float>(u(rng) * 0.05));
    p.time_offset_s = static_cast<float>((u(rng) + 20.0) / 400.0);
    p.ring = static_cast<std::int16_t>(i % 32);
    pts.push_back(p);
  }
  // Points exactly on voxel faces, at the origin and at negative faces, and a NaN.
  for (float v : {0.0f, -0.5f, 0.5f, -1.0f, -0.25f}) {
    LidarPoint p;
    p.p_lidar = Eigen::Vector3f(v, -v, v);
    pts.push_back(p);
  }
  pts.push_back(LidarPoint{});
  pts.back().p_lidar.x() = kNaN;

  for (float leaf : {0.5f, 0.25f, 0.1f, 1.0f}) {
    SCOPED_TRACE("leaf " + std::to_string(leaf));
    const auto out = voxelDownsample(pts, leaf);
    const auto ref = bruteGroups(pts, static_cast<double>(leaf));
    ASSERT_EQ(out.size(), ref.size());
    for (std::size_t v = 0; v < out.size(); ++v) {
      const Eigen::Vector3d c = ref[v].sum / ref[v].n;
      EXPECT_LT((out[v].p_lidar.cast<double>() - c).norm(), 1e-5);
      EXPECT_NEAR(out[v].time_offset_s, ref[v].t / ref[v].n, 1e-7);
      EXPECT_EQ(out[v].ring, pts[ref[v].first].ring);
    }
    // The Vector3d variant groups identically.
    std::vector<Eigen::Vector3d> pd;
    for (const LidarPoint& p : pts) pd.push_back(p.p_lidar.cast<double>());
    const auto outd = voxelDownsample(pd, static_cast<double>(leaf));
    ASSERT_EQ(outd.size(), ref.size());
    for (std::size_t v = 0; v < outd.size(); ++v) EXPECT_LT((outd[v] - ref[v].sum / ref[v].n).norm(), 1e-9);
  }
  EXPECT_EQ(voxelDownsample(pts, 0.f).size(), pts.size());
}

// ------------------------------------------------------------------ real scans (Newer College)

namespace {

std::vector<float> readFloats(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::vector<float> v;
  if (!in) return v;
  in.seekg(0, std::ios::end);
  v.resize(static_cast<std::size_t>(in.tellg()) / sizeof(float));
  in.seekg(0);
  in.read(reinterpret_cast<char*>(v.data()), static_cast<std::streamsize>(v.size() * sizeof(float)));
  return v;
}

// Scans raw_0N + times_0N at 10 Hz; point id in the intensity.
std::vector<LidarScan> newerCollegeScans() {
  std::vector<LidarScan> scans;
  int id = 0;
  for (int k = 0; k < 3; ++k) {
    const std::string dir = std::string(LIVO_SHARED_DATA) + "/kitti_newer_college_scans/newer_06/";
    const auto xyz = readFloats(dir + "raw_0" + std::to_string(k) + ".bin");
    const auto times = readFloats(dir + "times_0" + std::to_string(k) + ".bin");
    if (xyz.empty() || xyz.size() != 3 * times.size()) return {};
    LidarScan s;
    s.utime = kT0 + k * 100000;
    s.sensor = "ouster";
    for (std::size_t i = 0; i < times.size(); ++i) {
      LidarPoint p;
      p.p_lidar = Eigen::Vector3f(xyz[3 * i], xyz[3 * i + 1], xyz[3 * i + 2]);
      p.time_offset_s = times[i];
      p.intensity = static_cast<float>(id++);
      s.points.push_back(p);
    }
    scans.push_back(std::move(s));
  }
  return scans;
}

}  // namespace

TEST(NewerCollege, ScanCountsAndTimesSurviveRecombination) {
  const auto scans = newerCollegeScans();
  if (scans.empty()) GTEST_SKIP() << "no ../shared/data/kitti_newer_college_scans/newer_06";
  Scenario s;
  s.duration_s = 0.35;
  Data d = generate(s);  // IMU and 10 Hz images at phase 37 ms
  d.scans = scans;
  std::map<int, Utime> truth;
  std::size_t total = 0;
  for (const LidarScan& s : scans) {
    total += s.points.size();
    for (const LidarPoint& p : s.points) truth[static_cast<int>(p.intensity)] = s.utime + fromSeconds(p.time_offset_s);
  }
  EXPECT_EQ(total, 25109u + 20061u + 24649u);
  for (bool camera : {false, true}) {
    SCOPED_TRACE(camera ? "camera mode" : "lidar-only mode");
    PreprocessConfig c = testConfig(camera);
    c.blind_m = 0.0;
    Harness h(c);
    for (const Event& e : arrivalOrder(d))
      if (e.kind != 1 || e.index < scans.size()) h.feed(d, e);
    h.finish();
    const auto frame_of = checkFrames(h);
    const PreprocessStats& st = h.r.stats();
    EXPECT_EQ(st.points_in, total);
    EXPECT_EQ(st.points_nan + st.points_blind + st.points_range + st.points_bad_time, 0u);
    // Ouster sweeps last slightly more than 0.1 s (scan 0 ends at 0.1001 s): points of scan k+1 at or
    // before the end of frame k are late if frame k was emitted before scan k+1 arrived, and nothing
    // else is lost. (Here scan 0 is held for confirmation until scan 1 arrives, so none is late.)
    std::uint64_t overlap = 0;
    if (!camera) {
      ASSERT_EQ(h.frames.size(), 3u);
      for (std::size_t k = 0; k + 1 < scans.size(); ++k) {
        EXPECT_EQ(h.frames[k].utime, scans[k].utime + fromSeconds(scans[k].points.back().time_offset_s));
        for (const LidarPoint& p : scans[k + 1].points) overlap += truth[static_cast<int>(p.intensity)] <= h.frames[k].utime;
      }
      EXPECT_GT(overlap, 0u);
    }
    EXPECT_LE(st.points_late, overlap);
    EXPECT_EQ(frame_of.size() + h.r.pendingPoints() + st.points_late, total);
    for (const Frame& f : h.frames)
      for (const LidarPoint& p : f.sweep.points)
        EXPECT_NEAR(static_cast<double>(f.sweep.utime) + 1e6 * static_cast<double>(p.time_offset_s),
                    static_cast<double>(truth.at(static_cast<int>(p.intensity))), 1.0);
    std::cout << "[ newer_06 " << (camera ? "camera" : "lidar-only") << " ] " << h.frames.size() << " frames\n"
              << st.summary();
  }
}

TEST(NewerCollege, DownsampleTiming) {
  const auto scans = newerCollegeScans();
  if (scans.empty()) GTEST_SKIP() << "no ../shared/data/kitti_newer_college_scans/newer_06";
  for (float leaf : {0.1f, 0.2f, 0.5f}) {
    const int reps = 30;
    std::size_t out_size = 0;
    Stopwatch w;
    for (int r = 0; r < reps; ++r) out_size = voxelDownsample(scans[0].points, leaf).size();
    const double ms = w.elapsedMs() / reps;
    std::cout << "[ voxelDownsample ] " << scans[0].points.size() << " points, leaf " << leaf << " m -> "
              << out_size << " points, " << ms << " ms\n";
    EXPECT_LT(out_size, scans[0].points.size());
    EXPECT_GT(out_size, 100u);
  }
  // Recombiner cost per scan (filter, sort check, merge, cut), LiDAR-only frames, 30 scans.
  PreprocessConfig c = testConfig(false);
  Recombiner r(c);
  Frame f;
  double ms = 0.0;
  std::size_t points = 0, frames = 0;
  for (int k = 0; k < 30; ++k) {
    LidarScan s = scans[k % 3];
    s.utime = kT0 + k * 100000;
    ImuSample m;
    m.utime = s.utime + 120000;
    Stopwatch w;
    r.addScan(s);
    r.addImu(m);
    while (r.nextFrame(f)) {
      points += f.sweep.points.size();
      ++frames;
    }
    ms += w.elapsedMs();
  }
  std::cout << "[ Recombiner ] " << frames << " frames, " << points / std::max<std::size_t>(frames, 1)
            << " points per frame, " << ms / 30 << " ms per scan (add + cut)\n";
  EXPECT_GE(frames, 28u);
}
