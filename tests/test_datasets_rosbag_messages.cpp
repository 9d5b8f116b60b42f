// ROS 1 bag import of sensor messages: small bags written here with librosbag-storage (sensor_msgs types
// serialized by ROS's own generated code, Livox CustomMsg by hand), converted, read back from the LCM log
// and compared value by value with what was written: IMU (every chunk compression, acceleration in g),
// PointCloud2 layouts of the common drivers, Livox CustomMsg of both drivers.
// livo-test-deps: livo_io livo_rosbag_storage
#include "datasets_rosbag_test_util.hpp"

#include "test_skip.hpp"

#include <gtest/gtest.h>

using namespace livo;

#if !LIVO_TEST_ROSBAG

// Without librosbag-storage-dev (or without libsensor-msgs-dev, which the bag writers here need).
TEST(Rosbag, BuiltWithoutBagSupportSaysSo) {
  if (!rosbagSupported()) {
    try {
      convertRosbag("x.bag", "x.lcm");
      ADD_FAILURE() << "no error";
    } catch (const DatasetError& e) {
      EXPECT_NE(std::string(e.what()).find("no ROS bag support"), std::string::npos) << e.what();
    }
  }
  LIVO_SKIP() << "built without librosbag-storage-dev or libsensor-msgs-dev: bag tests skipped";
}

#endif

#if LIVO_TEST_ROSBAG

using namespace livo::test;

TEST(Rosbag, SupportIsBuiltIn) { EXPECT_TRUE(rosbagSupported()); }

TEST(Rosbag, LayoutMd5sMatchTheRosHeaders) {
  EXPECT_STREQ(rosLayoutMd5(RosType::Imu), ros::message_traits::MD5Sum<sensor_msgs::Imu>::value());
  EXPECT_STREQ(rosLayoutMd5(RosType::PointCloud2), ros::message_traits::MD5Sum<sensor_msgs::PointCloud2>::value());
  EXPECT_STREQ(rosLayoutMd5(RosType::Image), ros::message_traits::MD5Sum<sensor_msgs::Image>::value());
  EXPECT_STREQ(rosLayoutMd5(RosType::CompressedImage),
               ros::message_traits::MD5Sum<sensor_msgs::CompressedImage>::value());
  EXPECT_EQ(rosTypeOf("livox_ros_driver2/CustomMsg"), RosType::LivoxCustomMsg);
  EXPECT_EQ(rosTypeOf("std_msgs/String"), RosType::Unknown);
}

TEST(Rosbag, ImuValuesAndStampsWithEveryChunkCompression) {
  std::mt19937 rng(7);
  std::normal_distribution<double> noise(0.0, 0.3);
  const std::int64_t sub_us[5] = {0, 499, 500, 501, 999};  // ns parts that exercise the rounding
  for (auto compression : {rosbag::compression::Uncompressed, rosbag::compression::BZ2, rosbag::compression::LZ4}) {
    SCOPED_TRACE(static_cast<int>(compression));
    TempDir t;
    std::vector<std::int64_t> stamps;
    std::vector<Eigen::Vector3d> gyro, acc;
    {
      rosbag::Bag bag(t / "imu.bag", rosbag::bagmode::Write);
      bag.setCompression(compression);
      bag.setChunkThreshold(4096);
      for (int i = 0; i < 60; ++i) {
        stamps.push_back(kT0 + i * 5'000'000LL + sub_us[i % 5]);
        gyro.emplace_back(noise(rng), noise(rng), noise(rng));
        acc.push_back(Eigen::Vector3d(0.1, -0.2, 9.8) + Eigen::Vector3d(noise(rng), noise(rng), noise(rng)));
        bag.write("/imu", rosTime(stamps.back() + 2'000'000), imuMsg(stamps.back(), gyro.back(), acc.back()));
      }
    }
    const RosbagSummary s = convertRosbag(t / "imu.bag", t / "imu.lcm");
    EXPECT_TRUE(s.error.empty()) << s.error;
    EXPECT_EQ(s.topics.imu, "/imu");
    EXPECT_TRUE(contains(s.accel_note, "m/s^2")) << s.accel_note;
    const ReadBack r = readLog(t / "imu.lcm");
    ASSERT_EQ(r.imu.size(), stamps.size());
    for (std::size_t i = 0; i < stamps.size(); ++i) {
      EXPECT_EQ(r.imu[i].utime, roundUs(stamps[i])) << i;
      EXPECT_EQ(r.imu[i].gyro, gyro[i]) << i;  // float64 all the way: exact
      EXPECT_EQ(r.imu[i].accel, acc[i]) << i;
    }
  }
}

TEST(Rosbag, ImuAccelerationInGIsDetectedAndConverted) {
  TempDir t;
  {
    rosbag::Bag bag(t / "g.bag", rosbag::bagmode::Write);
    for (int i = 0; i < 30; ++i) {
      const std::int64_t st = kT0 + i * 5'000'000LL;
      bag.write("/livox/imu", rosTime(st), imuMsg(st, Eigen::Vector3d(0.01 * i, 0, 0), Eigen::Vector3d(0.02, -0.01, 1.0 + 0.001 * i)));
    }
  }
  RosbagSummary s = convertRosbag(t / "g.bag", t / "g.lcm");
  EXPECT_DOUBLE_EQ(s.accel_scale, 9.80665);
  EXPECT_TRUE(contains(s.accel_note, "in g detected")) << s.accel_note;
  ReadBack r = readLog(t / "g.lcm");
  ASSERT_EQ(r.imu.size(), 30u);
  for (int i = 0; i < 30; ++i) {
    EXPECT_DOUBLE_EQ(r.imu[i].accel.z(), (1.0 + 0.001 * i) * 9.80665);
    EXPECT_DOUBLE_EQ(r.imu[i].accel.x(), 0.02 * 9.80665);
    EXPECT_DOUBLE_EQ(r.imu[i].gyro.x(), 0.01 * i);  // gyro untouched
  }
  RosbagOptions keep;
  keep.imu_accel_unit = AccelUnit::MetresPerSecond2;
  s = convertRosbag(t / "g.bag", t / "g2.lcm", keep);
  EXPECT_DOUBLE_EQ(readLog(t / "g2.lcm").imu[5].accel.z(), 1.005);
  // Neither ~1 g nor ~9.8 m/s^2: kept, with a warning.
  std::string note;
  EXPECT_EQ(detectAccelScale({3.0, 3.1, 2.9}, RosbagOptions{}, note), 1.0);
  EXPECT_TRUE(contains(note, "WARNING")) << note;
}

TEST(Rosbag, PointCloud2LayoutsOfTheCommonDrivers) {
  using F = sensor_msgs::PointField;
  // Per layout: fields, and how the test expects the absolute time (ns) of a point to come out.
  struct Case {
    CloudSpec spec;
    std::function<PointValues(int i, int n, std::int64_t header_ns)> point;
    std::function<std::int64_t(const PointValues& v, std::int64_t header_ns)> abs_ns;  // -1: no times
    std::string ring_field, intensity_field;
  };
  auto xyz = [](int i) {
    return PointValues{{"x", 1.0 + 0.37 * i}, {"y", -2.0 + 0.11 * i}, {"z", 0.5 - 0.013 * i}};
  };
  std::vector<Case> cases;
  // Velodyne: time float32 s relative to the header, negative (header at the scan end), ring uint16.
  cases.push_back({{"velodyne", {{"x", F::FLOAT32, 0}, {"y", F::FLOAT32, 4}, {"z", F::FLOAT32, 8}, {"intensity", F::FLOAT32, 12},
                     {"ring", F::UINT16, 16}, {"time", F::FLOAT32, 18}}, 22},
                   [&](int i, int n, std::int64_t) { auto v = xyz(i); v["intensity"] = 3.5 * i; v["ring"] = i % 16; v["time"] = -0.1 + 0.1 * i / n; return v; },
                   [](const PointValues& v, std::int64_t h) { return h + std::llround(static_cast<double>(static_cast<float>(v.at("time"))) * 1e9); },
                   "ring", "intensity"});
  // Ouster: organized (4 rows), t uint32 ns, intensity float32, reflectivity uint16, ring uint8; both endians.
  for (bool be : {false, true})
    cases.push_back({{be ? "ouster_big_endian" : "ouster", {{"x", F::FLOAT32, 0}, {"y", F::FLOAT32, 4}, {"z", F::FLOAT32, 8},
                       {"intensity", F::FLOAT32, 16}, {"t", F::UINT32, 20}, {"reflectivity", F::UINT16, 24}, {"ring", F::UINT8, 26},
                       {"range", F::UINT32, 32}}, 48, 4, be},
                     [&](int i, int n, std::int64_t) { auto v = xyz(i); v["intensity"] = 100 + i; v["t"] = (i * 7919) % 99'000'000 + 13;
                       v["reflectivity"] = 7; v["ring"] = i / (n / 4); v["range"] = 1000; return v; },
                     [](const PointValues& v, std::int64_t h) { return h + static_cast<std::int64_t>(v.at("t")); }, "ring", "intensity"});
  // Hesai (Hilti 2022): timestamp float64 absolute s; header stamp at the scan end is not used.
  cases.push_back({{"hesai", {{"x", F::FLOAT32, 0}, {"y", F::FLOAT32, 4}, {"z", F::FLOAT32, 8}, {"intensity", F::FLOAT32, 12},
                     {"timestamp", F::FLOAT64, 16}, {"ring", F::UINT16, 24}}, 32},
                   [&](int i, int n, std::int64_t h) { auto v = xyz(i); v["intensity"] = i; v["ring"] = 31 - i % 32;
                     v["timestamp"] = static_cast<double>(h - 100'000'000) * 1e-9 + 0.1 * i / n; return v; },
                   [](const PointValues& v, std::int64_t) { return std::llround(v.at("timestamp") * 1e9); }, "ring", "intensity"});
  // livox_ros_driver2 PointCloud2: timestamp float64 absolute ns, line uint8.
  cases.push_back({{"livox2_pointcloud", {{"x", F::FLOAT32, 0}, {"y", F::FLOAT32, 4}, {"z", F::FLOAT32, 8}, {"intensity", F::FLOAT32, 12},
                     {"tag", F::UINT8, 16}, {"line", F::UINT8, 17}, {"timestamp", F::FLOAT64, 18}}, 26},
                   [&](int i, int, std::int64_t h) { auto v = xyz(i); v["intensity"] = 200 - i; v["tag"] = 0x10; v["line"] = i % 6;
                     v["timestamp"] = static_cast<double>(h + 1000 * i + 250); return v; },
                   [](const PointValues& v, std::int64_t) { return std::llround(v.at("timestamp")); }, "line", "intensity"});
  // Livox-style offset_time uint32 ns; reflectivity uint8 instead of intensity; unaligned fields.
  cases.push_back({{"offset_time_unaligned", {{"x", F::FLOAT32, 0}, {"y", F::FLOAT32, 4}, {"z", F::FLOAT32, 8},
                     {"reflectivity", F::UINT8, 12}, {"offset_time", F::UINT32, 13}, {"line", F::UINT8, 17}}, 18},
                   [&](int i, int n, std::int64_t) { auto v = xyz(i); v["reflectivity"] = 3 * i; v["line"] = i % 4;
                     v["offset_time"] = 100'000'000.0 * (n - i) / n; return v; },
                   [](const PointValues& v, std::int64_t h) { return h + static_cast<std::int64_t>(v.at("offset_time")); },
                   "line", "reflectivity"});
  // float64 coordinates, no time field: offsets 0, utime = header.
  cases.push_back({{"xyz64_untimed", {{"x", F::FLOAT64, 0}, {"y", F::FLOAT64, 8}, {"z", F::FLOAT64, 16}}, 24},
                   [&](int i, int, std::int64_t) { return xyz(i); }, nullptr, "", ""});

  for (const Case& c : cases) {
    SCOPED_TRACE(c.spec.name);
    TempDir t;
    const int n = 40;
    std::vector<std::vector<PointValues>> sent;
    std::vector<std::int64_t> headers;
    {
      rosbag::Bag bag(t / "c.bag", rosbag::bagmode::Write);
      for (int k = 0; k < 2; ++k) {
        headers.push_back(kT0 + k * 100'000'000LL + 777);
        std::vector<PointValues> pts;
        for (int i = 0; i < n; ++i) pts.push_back(c.point(i, n, headers.back()));
        if (c.spec.name == "velodyne") pts[3]["x"] = std::nan("");  // dropped
        bag.write("/points", rosTime(headers.back() + 100'000'000), cloudMsg(c.spec, headers.back(), pts));
        sent.push_back(pts);
      }
    }
    const RosbagSummary s = convertRosbag(t / "c.bag", t / "c.lcm");
    ASSERT_TRUE(s.error.empty()) << s.error;
    const ReadBack r = readLog(t / "c.lcm");
    ASSERT_EQ(r.scans.size(), 2u);
    for (int k = 0; k < 2; ++k) {
      std::vector<PointValues> expect;
      for (const auto& p : sent[k])
        if (std::isfinite(p.at("x"))) expect.push_back(p);
      const LidarScan& scan = r.scans[k];
      EXPECT_EQ(scan.sensor, "generic");
      ASSERT_EQ(scan.points.size(), expect.size());
      std::vector<std::int64_t> abs;
      for (const auto& p : expect) abs.push_back(c.abs_ns ? c.abs_ns(p, headers[k]) : headers[k]);
      const std::int64_t t_min = *std::min_element(abs.begin(), abs.end());
      EXPECT_EQ(scan.utime, c.abs_ns ? floorUs(t_min) : roundUs(headers[k]));
      for (std::size_t i = 0; i < expect.size(); ++i) {
        const LidarPoint& q = scan.points[i];
        EXPECT_EQ(q.p_lidar.x(), static_cast<float>(stored(c.spec, "x", expect[i].at("x")))) << i;
        EXPECT_EQ(q.p_lidar.y(), static_cast<float>(stored(c.spec, "y", expect[i].at("y")))) << i;
        EXPECT_EQ(q.p_lidar.z(), static_cast<float>(stored(c.spec, "z", expect[i].at("z")))) << i;
        const double off = c.abs_ns ? static_cast<double>(abs[i] - scan.utime * 1000) * 1e-9 : 0.0;
        EXPECT_NEAR(q.time_offset_s, off, 2e-8) << i;
        EXPECT_GE(q.time_offset_s, 0.f) << i;
        EXPECT_EQ(q.intensity, c.intensity_field.empty() ? 0.f : static_cast<float>(stored(c.spec, c.intensity_field, expect[i].at(c.intensity_field)))) << i;
        EXPECT_EQ(q.ring, c.ring_field.empty() ? -1 : static_cast<int>(expect[i].at(c.ring_field))) << i;
      }
    }
    if (c.spec.name == "velodyne") {
      EXPECT_TRUE(contains(s.describe(), "2 points with non-finite coordinates dropped")) << s.describe();
    }
    if (!c.abs_ns) {
      EXPECT_TRUE(contains(s.describe(), "without a per-point time field")) << s.describe();
    }
  }
}

TEST(Rosbag, LivoxCustomMsgOfBothDrivers) {
  for (const std::string datatype : {"livox_ros_driver/CustomMsg", "livox_ros_driver2/CustomMsg"}) {
    SCOPED_TRACE(datatype);
    TempDir t;
    std::vector<LivoxPoint> pts;
    for (int i = 0; i < 50; ++i)
      pts.push_back({static_cast<std::uint32_t>(1'000 + (i * 37) % 50 * 2'000'000LL), 0.5f * i, -0.25f * i, 0.125f + i,
                     static_cast<std::uint8_t>(5 * i), 0x10, static_cast<std::uint8_t>(i % 6)});
    pts[7].y = std::numeric_limits<float>::infinity();  // dropped
    const std::int64_t header = kT0 + 123'456'789;
    {
      rosbag::Bag bag(t / "l.bag", rosbag::bagmode::Write);
      bag.write("/livox/lidar", rosTime(header + 100'000'000), livoxMsg(datatype, header, pts));
    }
    const RosbagSummary s = convertRosbag(t / "l.bag", t / "l.lcm");
    ASSERT_TRUE(s.error.empty()) << s.error;
    const ReadBack r = readLog(t / "l.lcm");
    ASSERT_EQ(r.scans.size(), 1u);
    const LidarScan& scan = r.scans[0];
    EXPECT_EQ(scan.sensor, "avia");
    EXPECT_EQ(scan.utime, floorUs(header + 1'000));  // earliest offset_time is 1000 ns
    pts.erase(pts.begin() + 7);
    ASSERT_EQ(scan.points.size(), pts.size());
    for (std::size_t i = 0; i < pts.size(); ++i) {
      const LidarPoint& q = scan.points[i];
      EXPECT_EQ(q.p_lidar, Eigen::Vector3f(pts[i].x, pts[i].y, pts[i].z)) << i;
      EXPECT_EQ(q.intensity, pts[i].reflectivity) << i;
      EXPECT_EQ(q.ring, pts[i].line) << i;
      EXPECT_NEAR(q.time_offset_s, static_cast<double>(header + pts[i].offset_ns - scan.utime * 1000) * 1e-9, 2e-8) << i;
    }
  }
}

#endif  // LIVO_TEST_ROSBAG
