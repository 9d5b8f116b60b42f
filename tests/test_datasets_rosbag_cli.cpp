// ROS 1 bag import through the livo-convert binary, and an opt-in conversion speed figure on a ~100 MB bag.
// livo-test-deps: livo_io livo_rosbag_storage
// livo-test-bins: livo-convert
#include "datasets_rosbag_test_util.hpp"

#include "test_skip.hpp"

#include <gtest/gtest.h>

#include <sys/wait.h>

using namespace livo;

#if LIVO_TEST_ROSBAG

using namespace livo::test;

TEST(Rosbag, LivoConvertBinary) {
  const std::string bin = std::string(LIVO_BINARY_DIR) + "/bin/livo-convert";
  if (!fs::exists(bin)) LIVO_SKIP() << "binary not built: " << bin;
  TempDir t;
  writeImuBag(t / "b.bag", 20, rosbag::compression::LZ4);
  const std::string out = t / "b.lcm", txt = t / "out.txt", err = t / "err.txt";
  int rc = std::system((bin + " rosbag " + (t / "b.bag") + " --out " + out + " --imu-topic /imu --quiet > " + txt + " 2> " + err).c_str());
  EXPECT_EQ(rc, 0);
  std::ifstream f(txt);
  const std::string text((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
  EXPECT_TRUE(contains(text, "LIVO_IMU")) << text;
  EXPECT_EQ(readLog(out).imu.size(), 20u);
  rc = std::system((bin + " rosbag " + (t / "b.bag") + " --out " + (t / "x.lcm") + " --lidar-topic /nope 2> " + err).c_str());
  EXPECT_TRUE(WIFEXITED(rc) && WEXITSTATUS(rc) == 1) << "a run-time error, not a crash: status " << rc;
  std::ifstream e(err);
  const std::string etext((std::istreambuf_iterator<char>(e)), std::istreambuf_iterator<char>());
  EXPECT_TRUE(contains(etext, "no topic /nope (--lidar-topic)")) << etext;
}

// Opt-in figure: conversion speed on a ~100 MB bag of Velodyne-style clouds (random points) and 200 Hz IMU,
// per chunk compression. Run with --gtest_also_run_disabled_tests --gtest_filter=*ConversionSpeed*.
TEST(Rosbag, DISABLED_ConversionSpeed) {
  using F = sensor_msgs::PointField;
  const CloudSpec velo{"v", {{"x", F::FLOAT32, 0}, {"y", F::FLOAT32, 4}, {"z", F::FLOAT32, 8}, {"intensity", F::FLOAT32, 12},
                             {"ring", F::UINT16, 16}, {"time", F::FLOAT32, 18}}, 22};
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-50, 50);
  std::vector<PointValues> pts;
  for (int i = 0; i < 22'000; ++i)
    pts.push_back({{"x", u(rng)}, {"y", u(rng)}, {"z", u(rng) / 10}, {"intensity", i % 255}, {"ring", i % 32}, {"time", 0.1 * i / 22'000}});
  sensor_msgs::PointCloud2 m = cloudMsg(velo, kT0, pts);
  for (auto compression : {rosbag::compression::Uncompressed, rosbag::compression::LZ4, rosbag::compression::BZ2}) {
    TempDir t;
    {
      rosbag::Bag bag(t / "big.bag", rosbag::bagmode::Write);
      bag.setCompression(compression);
      for (std::int64_t k = 0; k < 200; ++k) {
        const std::int64_t st = kT0 + k * 100'000'000LL;
        for (std::int64_t i = 0; i < 20; ++i)
          bag.write("/imu", rosTime(st + i * 5'000'000LL), imuMsg(st + i * 5'000'000LL, {0, 0, 0}, {0, 0, 9.8}));
        m.header.stamp = rosTime(st);
        bag.write("/velodyne_points", rosTime(st + 99'900'000LL), m);  // no record-time ties across chunks
      }
    }
    const double mb = static_cast<double>(fs::file_size(t / "big.bag")) / (1 << 20);
    const auto t0 = std::chrono::steady_clock::now();
    const RosbagSummary s = convertRosbag(t / "big.bag", t / "big.lcm");
    const double sec = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    ASSERT_TRUE(s.error.empty());
    std::printf("compression %d: %.1f MiB bag (%llu messages, %.1f MiB of messages) converted in %.2f s: %.0f MiB/s of bag\n",
                static_cast<int>(compression), mb, static_cast<unsigned long long>(s.messages_read),
                static_cast<double>(s.conversion.file_bytes) / (1 << 20), sec, mb / sec);
  }
}

#endif  // LIVO_TEST_ROSBAG
