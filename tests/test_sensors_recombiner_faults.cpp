// libs/sensors: scan recombination on faulty synthetic streams (every fault counted, no stall when a sensor
// stops, bounded buffers, random faults keep the frame invariants).
#include "sensors_test_util.hpp"

#include "livo/sensors/preprocess_config.hpp"
#include "livo/sensors/recombiner.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <map>
#include <random>
#include <vector>

using namespace livo;
using namespace livo::test;

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
