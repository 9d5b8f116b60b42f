// libs/sensors: preprocessing config (rig sections, defaults, errors naming file and key) and point filtering
// against brute-force counts.
#include "sensors_test_util.hpp"

#include "livo/common/config.hpp"
#include "livo/sensors/preprocess_config.hpp"
#include "livo/sensors/preprocess_points.hpp"
#include "livo/sensors/recombiner.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

using namespace livo;
using namespace livo::test;

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
