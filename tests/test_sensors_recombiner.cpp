// libs/sensors: scan recombination on clean synthetic streams (every point in exactly one frame at the right
// place, IMU coverage), in camera and LiDAR-only mode.
#include "sensors_test_util.hpp"

#include "livo/sensors/preprocess_config.hpp"
#include "livo/sensors/recombiner.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <map>
#include <vector>

using namespace livo;
using namespace livo::test;

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
