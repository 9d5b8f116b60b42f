// Benchmark (disabled, not run by ctest): the demo's sensor rates through livo-ros-bridge and the four
// processes behind it, in the private network namespace of the bridge's tests (rosbridge_test_world.hpp):
//   build/bin/test_rosbridge_rates --gtest_also_run_disabled_tests
// livo-test-bins: livo-ros-bridge livo-sim livo-preprocess livo-estimator livo-mapserver livo-exporter
// livo-test-deps: livo_datasets livo_io livo_eval livo_rosbag_storage livo_ros_client opencv_core opencv_imgcodecs
#include "rosbridge_test_bag.hpp"
#include "test_skip.hpp"

#include <gtest/gtest.h>

#if !LIVO_TEST_ROSBAG || !defined(LIVO_HAVE_ROS_CLIENT)

TEST(RosBridgeRates, NeedsTheRosClientLibraries) {
  LIVO_SKIP() << "built without the ROS 1 client libraries (libroscpp-dev, libnav-msgs-dev, libtf2-msgs-dev, "
                 "libdiagnostic-msgs-dev, librosbag-storage-dev): livo-ros-bridge and its test are skipped";
}

#else

#include "rosbridge_test_world.hpp"

using namespace livo_rosbridge_test;

// 4. Benchmark (disabled): the demo scenario as a ROS bag (Avia-like PointCloud2 at 10 Hz, IMU at 200 Hz,
// 640 x 512 mono8 images at 10 Hz) played at its rate into the bridge, the four processes behind it and
// the odometry back on ROS. Prints the bridge's added latency and CPU (its --stats lines), the poses on
// ROS and the exported trajectory's ATE.
namespace {

/// The simulator's LCM log as the bag a ROS driver set would record (stamps = sensor time; a scan is
/// recorded at its end, like a driver publishes it).
void lcmLogToBag(const std::string& log, const std::string& bag_path) {
  using F = sensor_msgs::PointField;
  const CloudSpec spec{"avia", {{"x", F::FLOAT32, 0}, {"y", F::FLOAT32, 4}, {"z", F::FLOAT32, 8}, {"intensity", F::FLOAT32, 12},
                                {"ring", F::UINT16, 16}, {"time", F::FLOAT32, 18}}, 22};
  rosbag::Bag bag(bag_path, rosbag::bagmode::Write);
  LogReader reader(log);
  LogEvent ev;
  while (reader.next(ev)) {
    if (ev.channel == "LIVO_IMU") {
      livo::imu_t m;
      ImuSample s;
      ASSERT_TRUE(decode(ev.data.data(), ev.data.size(), m) && fromMsg(m, s));
      bag.write("/imu", rosTime(s.utime * 1000), imuMsg(s.utime * 1000, s.gyro, s.accel));
    } else if (ev.channel == "LIVO_LIDAR") {
      livo::lidar_scan_t m;
      LidarScan scan;
      ASSERT_TRUE(decode(ev.data.data(), ev.data.size(), m) && fromMsg(m, scan));
      std::vector<PointValues> pts;
      pts.reserve(scan.points.size());
      for (const LidarPoint& p : scan.points)
        pts.push_back({{"x", p.p_lidar.x()}, {"y", p.p_lidar.y()}, {"z", p.p_lidar.z()}, {"intensity", p.intensity},
                       {"ring", std::max<int>(p.ring, 0)}, {"time", p.time_offset_s}});
      bag.write("/livox/points", rosTime(scan.endUtime() * 1000), cloudMsg(spec, scan.utime * 1000, pts));
    } else if (ev.channel == "LIVO_CAMERA") {
      livo::image_t m;
      Image img;
      ASSERT_TRUE(decode(ev.data.data(), ev.data.size(), m) && fromMsg(m, img));
      sensor_msgs::Image r;
      r.header.stamp = rosTime(img.utime * 1000);
      r.height = img.height, r.width = img.width, r.encoding = "mono8", r.step = img.row_stride;
      r.data = img.data;
      bag.write("/camera/image", rosTime(img.utime * 1000), r);
    }
  }
}

}  // namespace

TEST(RosBridge, DISABLED_DemoRatesThroughTheSuite) {
  World& w = world();
  if (!w.ok) LIVO_SKIP() << w.why;
  const std::string d = w.dir + "/demo";
  std::filesystem::create_directories(d);
  ASSERT_EQ(std::system((kBin + "/livo-sim --quiet --scenario " + std::string(LIVO_SOURCE_DIR) + "/config/sim/demo.yaml --out " +
                         d + "/demo.lcm --gt " + d + "/gt.tum --rig " + d + "/rig.yaml > " + d + "/sim.txt 2>&1")
                            .c_str()),
            0)
      << readFile(d + "/sim.txt");
  lcmLogToBag(d + "/demo.lcm", d + "/demo.bag");
  const std::string rig = d + "/rig.yaml";
  auto proc = [&](const std::string& name, std::vector<std::string> extra) {
    std::vector<std::string> argv{kBin + "/livo-" + name, "--config", rig, "--lcm-url", kUrl};
    argv.insert(argv.end(), extra.begin(), extra.end());
    return std::make_unique<Child>(argv, d + "/" + name + ".txt");
  };
  auto mapserver = proc("mapserver", {});
  auto estimator = proc("estimator", {"--idle-exit", "6"});
  auto exporter = proc("exporter", {"--out", d + "/export", "--idle-exit", "10"});
  auto preprocess = proc("preprocess", {"--idle-exit", "30"});
  Child bridge({kBin + "/livo-ros-bridge", "--config", rig, "--lcm-url", kUrl, "--stats", "5"}, d + "/bridge.txt");
  RosListener ros_in;
  ASSERT_TRUE(waitUntil([&] { return ros_in.connected(); }, 30)) << readFile(d + "/bridge.txt");
  Child play({"rosbag", "play", "--wait-for-subscribers", "-q", d + "/demo.bag"}, d + "/play.txt");
  EXPECT_EQ(play.wait(120), 0) << readFile(d + "/play.txt");
  EXPECT_EQ(preprocess->wait(120), 0);  // idle exits once the bag is over
  EXPECT_EQ(estimator->wait(60), 0);
  EXPECT_EQ(exporter->wait(60), 0);
  bridge.signal(SIGINT);
  EXPECT_EQ(bridge.wait(30), 0);
  mapserver->signal(SIGINT);
  EXPECT_EQ(mapserver->wait(30), 0);
  std::cout << readFile(d + "/bridge.txt");
  const Trajectory gt = readTum(d + "/gt.tum"), est = readTum(d + "/export/trajectory.tum");
  std::cout << "demo through the bridge: " << ros_in.size(ros_in.odometry) << " odometry messages on ROS, "
            << est.size() << " poses exported, ATE " << 100 * evaluate(gt, est, EvalConfig{}).ate.translation_m.rmse
            << " cm\n";
  ros_in.subs.clear();
}

#endif
