// libs/sensors: real Newer College scans through recombination (counts and point times survive) and the
// cost of voxel downsampling and recombination on them.
#include "sensors_test_util.hpp"

#include "livo/common/timing.hpp"
#include "livo/sensors/downsample.hpp"
#include "livo/sensors/preprocess_config.hpp"
#include "livo/sensors/recombiner.hpp"

#include "test_skip.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <fstream>
#include <iostream>
#include <map>
#include <string>
#include <vector>

using namespace livo;
using namespace livo::test;

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
  if (scans.empty()) LIVO_SKIP() << "no ../shared/data/kitti_newer_college_scans/newer_06";
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
  if (scans.empty()) LIVO_SKIP() << "no ../shared/data/kitti_newer_college_scans/newer_06";
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
